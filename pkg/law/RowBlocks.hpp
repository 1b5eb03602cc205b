// Blocks of the rows of a Gauss-Seidel sweep (law/ImpulseLaw's impulse rows, law/PositionProjection's
// contacts): a sweep that runs on several threads with three barriers, and gives the same bits on any
// count.
//
// The rows' nodes are cut into kBlocks slabs across the widest extent of the rows (equal row counts
// per slab). A row whose nodes all lie in one slab belongs to that slab's block; blocks share no
// node, so they are solved at once, each block's rows one after another in row order, and the result
// is what solving the blocks one after another gives. The rows across one cut follow, the even cuts'
// at once, then the odd cuts' (the rows of cuts c and c + 2 share no node). The rows across two cuts
// or more (the seam) and the rows on a rigid body (the tail: all of a projectile's rows share it)
// follow, in row order, on one thread. This is block Gauss-Seidel with the interface last (the
// domain-decomposition ordering of Gauss-Seidel; Saad, "Iterative Methods for Sparse Linear
// Systems", 2nd ed., Sec. 12.4 and 14.2), still Gauss-Seidel, in another row order than the list's.
// Against law/RowColouring it costs three barriers per sweep instead of one per colour, and keeps
// the list's order (neighbouring rows one after another) inside each block.
//
// The blocks are a function of the row list and the node positions alone (kBlocks is fixed, not the
// thread count): the same order for any thread count.
#pragma once
#include "core/Parallel.hpp"
#include "core/Types.hpp"
#include "law/RowColouring.hpp"
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace woven {

class RowBlocks {
 public:
  /// Blocks of a sweep (fixed: the order must not depend on the thread count); 8 keep two to four
  /// threads busy with equal shares.
  static constexpr int kBlocks = 8;
  /// Groups in order(), solved in three phases, the groups of a phase at once (they share no node):
  /// the blocks 0 .. kBlocks - 1; the rows across the even cuts (cut c lies between blocks c and
  /// c + 1); those across the odd cuts; then, on one thread, the rows across two cuts or more (kSeam)
  /// and the tail (kTail).
  static constexpr int kPhases = 3;
  static constexpr int kSeam = kBlocks + kBlocks - 1, kTail = kSeam + 1;
  /// First group of phase p in [0, kPhases] (phase kPhases: the serial part).
  static constexpr int phaseBegin(int p) {
    return p == 0 ? 0 : p == 1 ? kBlocks : p == 2 ? kBlocks + kBlocks / 2 : kSeam;
  }

  /// Blocks rows [0, nRows): nodesOf(r, node) writes row r's nodes into node[0..kMaxRowNodes) and
  /// returns how many, or -1 for a row of the tail; pos: the node positions [m].
  template <class NodesOf>
  void build(Index nRows, const Vec3Array& pos, NodesOf&& nodesOf);

  /// Group of row r (a block, a cut, kSeam or kTail).
  int group(Index r) const { return group_[r]; }
  /// The rows by group, each group's rows in row order: group g is order()[begin(g) .. begin(g + 1)).
  const std::vector<Index>& order() const { return order_; }
  Index begin(int g) const { return start_[g]; }

 private:
  static constexpr int kBins = 64 * kBlocks;  // histogram of the rows along the cut axis
  struct RowNodes {
    Index node[kMaxRowNodes];
    int n;
  };
  std::vector<RowNodes> nodes_;
  // What each fixed chunk of rows adds up: the extent of its first nodes and its yarn rows, its
  // histogram, its rows per group and where they go in order().
  static constexpr Index kChunk = 4096;
  struct Chunk {
    Vec3 lo, hi;
    Index yarnRows = 0;
    std::array<Index, kBins> count;
    std::array<Index, kTail + 1> size, next;
  };
  std::vector<Chunk> chunks_;
  std::vector<std::uint8_t> group_;
  std::vector<Index> order_;
  std::array<Index, kTail + 2> start_ = {};
};

template <class NodesOf>
void RowBlocks::build(Index nRows, const Vec3Array& pos, NodesOf&& nodesOf) {
  group_.resize(static_cast<std::size_t>(nRows));
  // Each row's nodes, read once (a row is a large record; the passes below read these 20 bytes).
  // Every pass runs on the threads by fixed chunks of rows: a row's items are its own, and what the
  // chunks add up (extents, histograms, counts) are exact in any order, so the blocks are the same
  // on any thread count.
  nodes_.resize(static_cast<std::size_t>(nRows));
  parallelFor(nRows, kParallelGrain, threads(), [&](Index r) { nodes_[r].n = nodesOf(r, nodes_[r].node); });
  const Index chunks = chunkCount(nRows, kChunk);
  chunks_.resize(static_cast<std::size_t>(chunks));
  const auto rowsOf = [&](Index t, Index& r0, Index& r1) { r0 = t * kChunk, r1 = std::min(nRows, r0 + kChunk); };
  // The extent of the rows' first nodes, and the yarn rows (a row on a body has none).
  parallelFor(chunks, 2, threads(), [&](Index t) {
    Chunk& c = chunks_[t];
    c.lo = Vec3::Constant(std::numeric_limits<Real>::infinity()), c.hi = -c.lo, c.yarnRows = 0;
    Index r0, r1;
    rowsOf(t, r0, r1);
    for (Index r = r0; r < r1; ++r)
      if (nodes_[r].n > 0) c.lo = c.lo.cwiseMin(pos[nodes_[r].node[0]]), c.hi = c.hi.cwiseMax(pos[nodes_[r].node[0]]), ++c.yarnRows;
  });
  Vec3 lo = Vec3::Constant(std::numeric_limits<Real>::infinity()), hi = -lo;
  Index yarnRows = 0;
  for (const Chunk& c : chunks_) lo = lo.cwiseMin(c.lo), hi = hi.cwiseMax(c.hi), yarnRows += c.yarnRows;
  // The cuts run across the extent's widest axis, at equal row counts.
  int axis = 0;
  if (yarnRows > 0) (hi - lo).maxCoeff(&axis);
  const Real origin = yarnRows > 0 ? lo[axis] : 0, width = yarnRows > 0 ? hi[axis] - lo[axis] : 0;
  const Real perBin = width > 0 ? kBins / width : 0;
  const auto bin = [&](Index node) {
    const Real x = (pos[node][axis] - origin) * perBin;  // NaN-safe: !(x > 0) goes to bin 0
    return x > 0 ? std::min(static_cast<int>(x), kBins - 1) : 0;
  };
  // A histogram of the rows' first nodes; bins go to block b until b + 1 shares of the rows are in.
  parallelFor(chunks, 2, threads(), [&](Index t) {
    Chunk& c = chunks_[t];
    c.count.fill(0);
    Index r0, r1;
    rowsOf(t, r0, r1);
    for (Index r = r0; r < r1; ++r)
      if (nodes_[r].n > 0) ++c.count[bin(nodes_[r].node[0])];
  });
  std::array<Index, kBins> count = {};
  for (const Chunk& c : chunks_)
    for (int k = 0; k < kBins; ++k) count[k] += c.count[k];
  std::array<std::uint8_t, kBins> blockOf = {};
  Index below = 0;
  int b = 0;
  for (int k = 0; k < kBins; ++k) {
    while (b < kBlocks - 1 && below >= (b + 1) * yarnRows / kBlocks) ++b;
    blockOf[k] = static_cast<std::uint8_t>(b);
    below += count[k];
  }
  // Each row's group and each chunk's rows per group, then a stable counting sort by group: a
  // chunk's rows of group g go after the earlier chunks' rows of g.
  parallelFor(chunks, 2, threads(), [&](Index t) {
    Chunk& c = chunks_[t];
    c.size.fill(0);
    Index r0, r1;
    rowsOf(t, r0, r1);
    for (Index r = r0; r < r1; ++r) {
      const RowNodes& q = nodes_[r];
      int g = kTail;
      if (q.n > 0) {
        int lowest = kBlocks, highest = -1;
        for (int k = 0; k < q.n; ++k) {
          const int b = blockOf[bin(q.node[k])];
          lowest = std::min(lowest, b), highest = std::max(highest, b);
        }
        g = highest == lowest ? lowest
            : highest > lowest + 1 ? kSeam
            : lowest % 2 == 0 ? kBlocks + lowest / 2  // an even cut
                              : kBlocks + kBlocks / 2 + lowest / 2;  // an odd cut
      }
      group_[r] = static_cast<std::uint8_t>(g);
      ++c.size[g];
    }
  });
  start_[0] = 0;
  for (int g = 0; g <= kTail; ++g) {
    Index at = start_[g];
    for (Chunk& c : chunks_) c.next[g] = at, at += c.size[g];
    start_[g + 1] = at;
  }
  order_.resize(static_cast<std::size_t>(nRows));
  parallelFor(chunks, 2, threads(), [&](Index t) {
    Chunk& c = chunks_[t];
    Index r0, r1;
    rowsOf(t, r0, r1);
    for (Index r = r0; r < r1; ++r) order_[c.next[group_[r]]++] = r;
  });
}

}  // namespace woven
