// Reference collider: sort-and-sweep over the world-axis-aligned boxes (AABBs) of all CPs along x,
// then the same separating-axis overlap test on the CPs' broad-phase OBBs as the tree's leaves. It
// knows nothing about yarns, so it checks YarnTreeCollider (same pairs) and is its speed baseline.
#pragma once
#include "collider/CandidatePairs.hpp"

namespace woven {

class SweepAndPrune {
 public:
  /// Sorted candidate pairs of CPs whose `boxes` overlap into `pairs`.
  void collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter, std::vector<CPPair>& pairs);
  long overlapTests = 0;  ///< OBB tests after the AABB sweep

 private:
  std::vector<Real> lo_, hi_;  // AABBs, 3 per CP
  std::vector<Index> order_;
};

}  // namespace woven
