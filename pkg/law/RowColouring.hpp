// Colours of the rows of a Gauss-Seidel sweep (law/ImpulseLaw's impulse rows, law/PositionProjection's
// contacts), so that a sweep runs on several threads and gives the same bits on any count.
//
// Rows of one colour share no node: each writes only its own nodes, and reads only them, so solving
// them at once, in any order, gives what solving them one after another does. The colours are
// solved in order, each after the one before: a coloured Gauss-Seidel sweep (the classic
// red-black / multi-colour ordering of Gauss-Seidel; Saad, "Iterative Methods for Sparse Linear
// Systems", 2nd ed., Sec. 12.4), still Gauss-Seidel, in another row order than the row list's.
// Rows that touch a rigid body (all of a projectile's rows share it) and rows that find none of the
// kColours colours free go to a serial tail, solved last, in row order.
//
// The colouring is greedy in row order (each row takes the smallest colour none of its nodes has
// yet), so it is a function of the row list alone: the same colours for any thread count.
#pragma once
#include "core/Types.hpp"
#include <algorithm>
#include <cstdint>
#include <vector>

namespace woven {

/// Most nodes a row (or a projected contact) reads: a persistent crossing's two lines
/// (GapFunction's kMaxStencil).
constexpr int kMaxRowNodes = 6;

class RowColouring {
 public:
  /// Colours held in a node's 64-bit mask; the tail is colour kColours.
  static constexpr int kColours = 64;

  /// Colours rows [0, nRows) over nodes [0, nNodes): nodesOf(r, node) writes row r's nodes into
  /// node[0..kMaxRowNodes) and returns how many, or -1 for a row of the serial tail.
  template <class NodesOf>
  void build(Index nRows, Index nNodes, NodesOf&& nodesOf);

  /// Colour of row r (kColours: the serial tail).
  int colour(Index r) const { return colour_[r]; }
  /// The rows by colour, each colour's rows in row order, the tail last: colour c is
  /// order()[begin(c) .. begin(c + 1)), c in [0, kColours].
  const std::vector<Index>& order() const { return order_; }
  Index begin(int c) const { return start_[c]; }
  /// Colours in use (the highest non-empty colour below the tail, plus one).
  int colours() const { return used_; }

 private:
  std::vector<std::uint64_t> mask_;  // per node: the colours its rows have taken (zero between builds)
  std::vector<Index> marked_;        // nodes whose mask is set
  std::vector<std::uint8_t> colour_;
  std::vector<Index> order_;
  Index start_[kColours + 2] = {};
  int used_ = 0;
};

template <class NodesOf>
void RowColouring::build(Index nRows, Index nNodes, NodesOf&& nodesOf) {
  colour_.resize(static_cast<std::size_t>(nRows));
  if (mask_.size() < static_cast<std::size_t>(nNodes)) mask_.resize(static_cast<std::size_t>(nNodes), 0);
  Index count[kColours + 1] = {};
  used_ = 0;
  for (Index r = 0; r < nRows; ++r) {
    Index node[kMaxRowNodes];
    const int n = nodesOf(r, node);
    std::uint64_t taken = 0;
    for (int k = 0; k < n; ++k) taken |= mask_[node[k]];
    const int c = n < 0 || taken == ~std::uint64_t(0) ? kColours : __builtin_ctzll(~taken);
    colour_[r] = static_cast<std::uint8_t>(c);
    ++count[c];
    if (c == kColours) continue;
    used_ = std::max(used_, c + 1);
    for (int k = 0; k < n; ++k) {
      if (mask_[node[k]] == 0) marked_.push_back(node[k]);
      mask_[node[k]] |= std::uint64_t(1) << c;
    }
  }
  for (Index i : marked_) mask_[i] = 0;
  marked_.clear();
  // Counting sort by colour, stable: each colour's rows in row order.
  start_[0] = 0;
  for (int c = 0; c <= kColours; ++c) start_[c + 1] = start_[c] + count[c];
  Index next[kColours + 1];
  for (int c = 0; c <= kColours; ++c) next[c] = start_[c];
  order_.resize(static_cast<std::size_t>(nRows));
  for (Index r = 0; r < nRows; ++r) order_[next[colour_[r]]++] = r;
}

}  // namespace woven
