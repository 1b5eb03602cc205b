// Collider on a uniform grid of cells as large as the largest CP box: each CP's world-axis-aligned
// box (AABB) is entered in the at most 8 cells it touches (a hash table of cells), and each CP is
// paired with the later CPs in its cells whose AABBs overlap its own; a pair seen in several common
// cells is kept only in the cell of the lowest corner of the two AABBs' intersection. The final test
// is the same separating-axis overlap on the same boxes, in the same argument order, as the OBB tree
// and sweep and prune, so the three return the same sorted pairs (tested against brute force).
//
// For a woven ply every warp root box overlaps every weft root box, so the tree descends all
// warp-weft crossings; the grid only meets the CPs that share a cell. It keeps no state between
// calls (no refit): cost in proportion to the number of CPs.
#pragma once
#include "collider/CandidatePairs.hpp"
#include <cstdint>

namespace woven {

class GridCollider {
 public:
  /// Sorted candidate pairs of CPs whose `boxes` overlap into `pairs`. With `dirty` (one flag per
  /// CP), only the pairs that involve a flagged CP are listed: the cells hold every CP, and only the
  /// flagged ones look in theirs. Each box must hold its CP's axis as it is now (a bound, grown or
  /// not): a point of both boxes between the two axes then answers the overlap before the test.
  void collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter, std::vector<CPPair>& pairs,
               const std::vector<std::uint8_t>* dirty = nullptr);
  long overlapTests = 0;  ///< OBB tests after the AABB test
  Real cellSize = 0;      ///< of the last call [m]

 private:
  struct Cell {
    std::int64_t x, y, z;
  };
  std::vector<Vec3> lo_, hi_;              // AABBs
  std::vector<Cell> cellLo_, cellHi_;      // each CP's range of cells (lowest and highest per axis)
  std::vector<Cell> cellOf_;               // the cells of each CP: cellBegin_[i] .. cellBegin_[i+1]
  std::vector<std::uint32_t> cellSlot_;     // the hash slot of each of those cells
  std::vector<Index> cellCP_;               // and its CP
  std::vector<Index> cellBegin_;
  std::vector<Real> chunkSide_;            // largest AABB side of each fixed chunk of CPs
  std::vector<std::uint32_t> slotCount_;   // hash table: entries per slot, then their start
  std::vector<std::uint32_t> fill_;        // next free entry of each slot while scattering
  std::vector<std::uint32_t> partTotal_;   // entries before each thread's range of slots
  std::vector<Index> slotItem_, slotCell_;  // per entry: the CP and its cell (index into cellOf_)
  std::vector<std::vector<CPPair>> chunkPairs_;  // pairs of each fixed chunk of CPs
  std::vector<long> chunkTests_;                 // OBB tests of each chunk
};

}  // namespace woven
