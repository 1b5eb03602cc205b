// Collider: an OBB tree per yarn over its consecutive CPs (paper Sec. 6.3: the boxes of a yarn nest
// into larger boxes of neighbouring pieces), plus a sweep over the yarns' root boxes across yarns.
//
// Each tree is balanced and fixed in shape (a yarn's CPs never reorder). Every step it is refitted
// bottom up: leaves are the CPs' broad-phase boxes; an internal node keeps its axes and only
// re-projects its two children on them (cheap). When a node's volume grows past `rebuildRatio`
// times its volume at its last rebuild (the yarn turned or bent under it), its axes are rebuilt
// from the chord of its CPs. Candidate pairs come from a simultaneous descent of two trees (or of a
// tree with itself) with the separating-axis overlap test.
#pragma once
#include "collider/CandidatePairs.hpp"

namespace woven {

class YarnTreeCollider {
 public:
  /// A node's axes are rebuilt when its volume exceeds this factor times its volume at its last
  /// rebuild [-] (> 1).
  Real rebuildRatio = 1.5;

  /// Sorted candidate pairs of CPs whose broad-phase `boxes` overlap (one per CP) into `pairs`.
  /// Builds the trees on the first call or when the fabric's yarn layout changed.
  /// With `dirty` (one flag per yarn), only the pairs that involve a flagged yarn are listed.
  void collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter, std::vector<CPPair>& pairs,
               const std::vector<std::uint8_t>* dirty = nullptr);

  struct Stats {
    long rebuiltNodes = 0;   ///< internal nodes whose axes were rebuilt (all of them at the first call)
    long overlapTests = 0;   ///< box-box tests in the descents
  };
  Stats stats;

 private:
  struct Node {
    OBB box;
    Real refVolume = 0;      // volume at the last rebuild of the axes; 0: never built
    Index lo = 0, hi = 0;    // CPs [lo, hi)
    Index left = -1, right = -1;
    bool leaf() const { return left < 0; }
  };
  Index buildRange(Index lo, Index hi);
  void build(const Fabric& f);
  // nodes [first, last), bottom up; returns the nodes whose axes were rebuilt
  long refitRange(const std::vector<OBB>& boxes, Index first, Index last);
  // pairs of the subtrees p and q into pairs (stack: scratch); returns the box tests made
  long descend(const Fabric& f, Index p, Index q, const PairFilter& filter, std::vector<CPPair>& pairs,
               std::vector<std::pair<Index, Index>>& stack) const;

  std::vector<Node> nodes_;  // pre-order: children after their parent
  std::vector<Index> root_;  // per yarn (-1 for a yarn with no CP)
  std::vector<Index> layout_;  // first element and count of each yarn, to detect a changed fabric
  std::vector<std::vector<CPPair>> spanPairs_;  // pairs found from each root span
  std::vector<long> perYarn_;                   // rebuilt nodes per yarn, then box tests per span
};

}  // namespace woven
