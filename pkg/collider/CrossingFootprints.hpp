// Which CP pairs the persistent crossings stand for (engine/CrossingContacts). A crossing's
// footprint is a run of CPs on each of its two yarns, those within the other yarn's widest
// half-width of its point; every pair of a CP of one run and a CP of the other is the crossing,
// seen piecewise, and is left out of the general pipeline's every stage (PairFilter: the broad
// phases; the candidate list and the narrow phase's contacts when a crossing forms or moves).
// Per CP the crossings whose footprint holds it, in a fixed number of slots: a pair is covered when
// its two CPs share one.
#pragma once
#include "core/Types.hpp"
#include <array>
#include <vector>

namespace woven {

class CrossingFootprints {
 public:
  /// Crossings one CP can be part of: two at its end nodes in a ply, more where plies press on each
  /// other. A crossing that would need a ninth is not formed (the general pipeline keeps its pairs).
  static constexpr int kPerCP = 8;
  using Slots = std::array<Index, kPerCP>;

  /// No crossing, for n CPs.
  void reset(Index n) { owners_.assign(static_cast<std::size_t>(n), empty()); }
  Index size() const { return static_cast<Index>(owners_.size()); }

  /// Whether CPs a and b share a crossing.
  bool covers(Index a, Index b) const {
    const Slots &A = owners_[a], &B = owners_[b];
    for (int i = 0; i < kPerCP && A[i] >= 0; ++i)
      for (int j = 0; j < kPerCP && B[j] >= 0; ++j)
        if (A[i] == B[j]) return true;
    return false;
  }
  /// Whether every CP of [a0, a1] and [b0, b1] has a free slot.
  bool room(Index a0, Index a1, Index b0, Index b1) const {
    for (Index e = a0; e <= a1; ++e)
      if (owners_[e][kPerCP - 1] >= 0) return false;
    for (Index e = b0; e <= b1; ++e)
      if (owners_[e][kPerCP - 1] >= 0) return false;
    return true;
  }
  /// Crossing `id` holds the CPs of [a0, a1] and [b0, b1] (room() first).
  void add(Index id, Index a0, Index a1, Index b0, Index b1) {
    for (Index e = a0; e <= a1; ++e) insert(owners_[e], id);
    for (Index e = b0; e <= b1; ++e) insert(owners_[e], id);
  }
  void remove(Index id, Index a0, Index a1, Index b0, Index b1) {
    for (Index e = a0; e <= a1; ++e) erase(owners_[e], id);
    for (Index e = b0; e <= b1; ++e) erase(owners_[e], id);
  }
  /// A crossing's index changed (the list was compacted): from -> to in its CPs' slots.
  void rename(Index from, Index to, Index a0, Index a1, Index b0, Index b1) {
    for (Index e = a0; e <= a1; ++e) swapId(owners_[e], from, to);
    for (Index e = b0; e <= b1; ++e) swapId(owners_[e], from, to);
  }
  const Slots& of(Index e) const { return owners_[e]; }

 private:
  static Slots empty() {
    Slots s;
    s.fill(-1);
    return s;
  }
  static void insert(Slots& s, Index id) {
    for (Index& x : s)
      if (x < 0) {
        x = id;
        return;
      }
  }
  static void erase(Slots& s, Index id) {
    int k = 0;
    for (int i = 0; i < kPerCP; ++i)
      if (s[i] != id) s[k++] = s[i];
    for (; k < kPerCP; ++k) s[k] = -1;
  }
  static void swapId(Slots& s, Index from, Index to) {
    for (Index& x : s)
      if (x == from) x = to;
  }
  std::vector<Slots> owners_;
};

}  // namespace woven
