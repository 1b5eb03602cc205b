// The collision stage's persistent crossings (engine/CrossingContacts: one carried contact per
// crossing): tracked before the broad phase, their returned pairs seeded with their side, measured
// and formed after the narrow phase.
#include "engine/CollisionStage.hpp"
#include "core/Parallel.hpp"
#include "engine/StageUtil.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

using namespace stage;  // engine/StageUtil.hpp

void CollisionStage::trackCrossings(const Fabric& f) {
  if (!params_.persistentCrossings()) {
    filter_.crossings = nullptr;
    if (!crossings_.empty()) crossings_.reset(Fabric{}), pairsValid_ = false;
    return;
  }
  if (crossings_.footprints().size() != f.nElems()) crossings_.reset(f);
  filter_.crossings = &crossings_.footprints();
  renew_.assign(static_cast<std::size_t>(f.nElems()), 0);
  if (crossings_.track(f, params_, chords_.unit, renew_)) {  // footprints moved onto new CPs: their pairs leave
    crossings_.exclude(pairs_);
    pairsChanged_ = true;
  }
}

// The pairs the crossings returned this step start from the crossing's side, their measure held to
// the room their axes leave (PairMemo::held): the chords, which run inside a crossing's curves by up
// to a few percent of the thickness, take over without an overlap the curves did not have. Only a
// pair whose axes lie on that side: a pair of the footprint far from the crossing's point may lie
// otherwise (a folded or broken piece), and held to the crossing's side it read its axes' distance as
// an overlap (254 um, a cube at 1000 m/s); it starts as a new pair, from its own geometry.
void CollisionStage::seedReturned(const Fabric& f) {
  for (const ReturnedFootprint& r : crossings_.returned())
    for (Index a = r.a0; a <= r.a1; ++a)
      for (auto it = std::lower_bound(pairs_.begin(), pairs_.end(), CPPair{a, r.b0});
           it != pairs_.end() && it->a == a && it->b <= r.b1; ++it) {
        PairMemo& pc = memo_[it - pairs_.begin()];
        if (pc.memo) continue;
        const Index i = f.elem0[it->a], j = f.elem0[it->b];
        const SegmentClosest sc = closestSegmentSegment(f.pos[i], f.pos[i + 1], f.pos[j], f.pos[j + 1]);
        const Vec3 d = ((1 - sc.t) * f.pos[j] + sc.t * f.pos[j + 1]) - ((1 - sc.s) * f.pos[i] + sc.s * f.pos[i + 1]);
        if (d.dot(r.normal) <= 0) continue;
        pc.memo = true, pc.side = false, pc.held = true, pc.memoPoints = 0;
        pc.memoNormal[0] = pc.memoNormal[1] = r.normal;
      }
}

void CollisionStage::measureCrossings(const Fabric& f, Real dt, bool formNew) {
  if (!params_.persistentCrossings()) return;
  if (formNew && crossings_.form(f, contacts_, params_, chords_.unit)) {
    // The new crossings' chord pairs leave the candidates and this step's contacts.
    crossings_.exclude(pairs_);
    crossings_.exclude(contacts_);
    pairsChanged_ = true;
  }
  // Listed as the CP pairs are (narrow), the lines' points moving no faster than the fastest node
  // of their CP and its neighbours (the nodes they read: YarnCurve's convex weights).
  const Real projected = projectionReach(dt);
  crossings_.measure(f, params_,
                     [&](const CPContact& c) {
                       return params_.margin +
                              2 * projected + dt * (fastestNear(f, c.cpA) + fastestNear(f, c.cpB));
                     },
                     contacts_);
  stats.crossings = crossings_.counts;
}

}  // namespace woven
