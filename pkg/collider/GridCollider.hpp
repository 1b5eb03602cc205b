// Collider on a uniform grid of cells as large as the largest CP box: each CP's world-axis-aligned
// box (AABB) is entered in the cells it touches (a hash map of cells), and each CP is paired with the
// later CPs in its cells whose AABBs overlap its own; a pair seen in several common cells is kept only
// in the cell of the lowest corner of the two AABBs' intersection. The final test is the same
// separating-axis overlap on the same boxes, in the same argument order, as the OBB tree and sweep
// and prune, so the three return the same sorted pairs (tested against brute force).
//
// For a woven ply every warp root box overlaps every weft root box, so the tree descends all
// warp-weft crossings; the grid only meets the CPs that share a cell.
//
// The grid persists between calls: a full call builds it from every box (and sets the cell size); a
// partial call (a flag per CP: the CPs whose boxes changed, CollisionStage's skin) moves only the
// flagged CPs to their new cells and lists only their pairs. The unflagged CPs' boxes must be the
// ones the grid holds. Under the default impact 2-45 % of the ply's CPs leave their skin in a step,
// and rebuilding the whole grid for them each step was the broad phase's cost. The pairs found do
// not depend on the cell size (a pair is listed in the cell of its intersection's lowest corner,
// whatever the cells), so a grid whose boxes grew past its cells is exact, only slower; a partial
// call whose live boxes span more than kMaxSpan cells along an axis rebuilds it (a broken CP only
// leaves the grid, however far its box has flown).
#pragma once
#include "collider/CandidatePairs.hpp"
#include <cstdint>
#include <vector>

namespace woven {

class GridCollider {
 public:
  /// Sorted candidate pairs of CPs whose `boxes` overlap into `pairs`. With `dirty` (one flag per
  /// CP), only the pairs that involve a flagged CP are listed: the flagged CPs move to the cells of
  /// their boxes now (the others' boxes must be those of the last call), and only they look in
  /// theirs. Each box must hold its CP's axis as it is now (a bound, grown or not): a point of both
  /// boxes between the two axes then answers the overlap before the test.
  void collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter, std::vector<CPPair>& pairs,
               const std::vector<std::uint8_t>* dirty = nullptr);
  long overlapTests = 0;  ///< OBB tests after the AABB test
  Real cellSize = 0;      ///< of the grid [m]
  long rebuilds = 0;      ///< full builds of the grid

  /// A partial call rebuilds the grid when a flagged live CP's box spans more cells than this along
  /// an axis.
  static constexpr int kMaxSpan = 4;

 private:
  struct Cell {
    std::int64_t x, y, z;
    bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto part = [](std::int64_t v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1fffff; };
    return part(x) << 42 | part(y) << 21 | part(z);
  }
  void aabb(const std::vector<OBB>& boxes, Index i);
  Cell cellOf(const Vec3& x) const;
  void insert(Index i);
  void remove(Index i);
  bool rebuild(const Fabric& f, const std::vector<OBB>& boxes);
  struct Aabb {
    Vec3 lo, hi;
  };
  std::vector<Aabb> aabb_;                 // AABBs as the grid holds them (a CP's corners together)
  std::vector<Cell> cellLo_, cellHi_;      // each CP's range of cells (lowest and highest per axis)
  std::vector<std::uint8_t> held_;         // per CP: in the grid (alive at its last entry)
  // The occupied cells by key: open addressing with linear probing in a power-of-two table at most
  // half full, each cell's CPs in a vector of its own. A std::unordered_map's lookups (a node per
  // cell, its hash modulo a prime) were most of a partial call's time.
  class CellTable {
   public:
    void clear();                                          // every cell gone (their storage kept)
    std::vector<Index>& at(std::uint64_t key);             // the cell, added if new
    const std::vector<Index>* find(std::uint64_t key) const;  // the cell, or null
   private:
    static constexpr std::uint64_t kFree = ~std::uint64_t(0);  // no key has its top bit set
    std::size_t slot(std::uint64_t key) const { return (key * 0x9E3779B97F4A7C15ull) >> shift_ & mask_; }
    void grow();
    std::vector<std::uint64_t> keys_;
    std::vector<std::vector<Index>> cells_;
    std::size_t used_ = 0, mask_ = 0;
    int shift_ = 64;
  };
  CellTable cells_;
  Real inverse_ = 0;                       // 1 / cellSize
  std::vector<Real> chunkSide_;            // largest AABB side of each fixed chunk of CPs
  std::vector<std::vector<CPPair>> chunkPairs_;  // pairs of each fixed chunk of CPs
  std::vector<long> chunkTests_;                 // OBB tests of each chunk
  std::vector<Index> flagged_;                   // the CPs a partial call lists pairs for
  std::vector<Index> moving_;                    // ... of which those that change cells
};

}  // namespace woven
