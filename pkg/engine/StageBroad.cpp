// The collision stage's bound functor and broad phase: each CP's OBB grown by its motion in the step
// (refit), the skin boxes and the candidate pairs they keep (broad: the grid, the OBB tree or sweep and
// prune), and the candidate pairs on demand (candidatePairs).
#include "engine/CollisionStage.hpp"
#include "bound/CPBound.hpp"
#include "core/Parallel.hpp"
#include "engine/StageUtil.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

using namespace stage;  // engine/StageUtil.hpp

namespace {
// Box a lies inside box b: on each of b's axes, a's projection lies within b's slab.
bool inside(const OBB& a, const OBB& b) {
  const Vec3 d = b.axes.transpose() * (a.centre - b.centre);
  const Mat3 c = (b.axes.transpose() * a.axes).cwiseAbs();
  return ((d.cwiseAbs() + c * a.extent).array() <= b.extent.array()).all();
}
}  // namespace

// One pass over the nodes (section frames, odometers), then one over the CPs (every per-CP figure
// below, each by its own expression: the same bits as a pass per figure, without re-reading the
// boxes between passes).
void CollisionStage::refit(Fabric& f, Real dt) {
  horizon_ = dt;
  if (filter_.yarnExclude.size() != f.yarns.size())
    filter_.configure(f, params_.selfExclude,
                      params_.model == ContactModel::Gap ? semiAxes(1, params_.mcd, params_.rule).a : 1.0);
  // Each node's section frame turned with its yarn (bound/CPBound's updateSectionFrames), and its
  // odometer: the path it has travelled between the passes (at least its displacement, however it
  // moved: drifts, projections, checks).
  tangent_.resize(f.pos.size());
  if (lastPos_.size() != f.pos.size()) lastPos_ = f.pos, travelled_.assign(f.pos.size(), 0.0);
  parallelFor(f.nNodes(), kParallelGrain, threads(), [&](Index k) {
    turnSectionFrame(f, k, tangent_);
    travelled_[k] += (f.pos[k] - lastPos_[k]).norm();
    lastPos_[k] = f.pos[k];
  });
  // Per CP: its OBB (bounds_); its faster node's speed, and the box grown by the farthest its nodes
  // can drift in the step and (gap model) be moved by the position projection after it (grown_);
  // its odometer, its two nodes' sum (the narrow phase's screen bounds how far a pair's axes have
  // come since it last measured them); model Gap: its unit chord and length, once for the four or
  // so pairs that share it and the crossings; and whether its grown box left the skin box of the
  // last broad phase (broad).
  const Index ne = f.nElems();
  bounds_.resize(ne), grown_.resize(ne), grow_.resize(ne), speed_.resize(ne), odometer_.resize(ne);
  const bool gap = params_.model == ContactModel::Gap;
  if (gap) chords_.unit.resize(ne), chords_.length.resize(ne);
  const bool skins = skinBoxes_.size() == static_cast<std::size_t>(ne);
  leftSkin_.resize(ne);
  const Real projected = projectionReach(dt);
  parallelFor(ne, kParallelGrain, threads(), [&](Index e) {
    const Index i = f.elem0[e];
    bounds_[e] = cpBound(f, tangent_, e, params_.rule, params_.margin);
    speed_[e] = std::sqrt(std::max(f.vel[i].squaredNorm(), f.vel[i + 1].squaredNorm()));
    grow_[e] = dt * speed_[e] + projected;
    grown_[e] = bounds_[e];
    grown_[e].extent.array() += grow_[e];
    odometer_[e] = travelled_[i] + travelled_[i + 1];
    if (gap) {
      const Vec3 d = f.pos[i + 1] - f.pos[i];
      chords_.unit[e] = d.normalized();
      chords_.length[e] = d.norm();
    }
    leftSkin_[e] = !skins || !inside(grown_[e], skinBoxes_[e]);
  });
}

// A renewed CP's skin box: its grown box with the skin on every side, stretched kSkinSteps steps
// ahead along its mean velocity. A CP carried by the impact's waves then stays inside for several
// steps where it left a 40 um skin every few, and the box grows only the way it moves: over the
// default impact's 100 us, 600 CPs a step re-collided instead of 1 481 (of 9 384, each ~4 us in the
// grid), the broad phase 5.1 s instead of 7.7; 4 steps ahead 824, 16 steps 415 CPs but more
// candidates and no faster; an isotropic skin of 120 um 516 CPs a step but 35 600 candidates
// (24 600) and no faster either. The contacts do not depend on the boxes (the narrow phase decides
// each pair on its own): the same bits for any skin (Threads.BallisticSceneIsTheSameBits...).
OBB CollisionStage::skinBox(const Fabric& f, Index e) const {
  OBB b = grown_[e];
  b.extent.array() += params_.skin;
  const Index i = f.elem0[e];
  const Vec3 ahead = (0.5 * kSkinSteps * horizon_) * (f.vel[i] + f.vel[i + 1]);
  if (ahead.allFinite()) {
    b.centre += 0.5 * ahead;
    b.extent += 0.5 * (b.axes.transpose() * ahead).cwiseAbs();
  }
  return b;
}

// The candidate pairs of the last broad phase hold as long as every CP's box stays inside the box
// that phase used (its box then, grown by the skin): a pair whose boxes overlap now overlapped then.
// Only the CPs out of their skin boxes (the grid), or the yarns that hold one (the OBB tree), are
// collided again, their skin boxes renewed: the pairs between two that stayed inside still hold.
// Under the default impact that is 2-45 % of the ply's CPs, where a full phase took them all at 128
// of 150 steps. The contacts are the same as with a full broad phase: the narrow phase decides each
// pair on its own, and a pair it does not measure forgets its memory as one the broad phase did not
// list.
void CollisionStage::broad(const Fabric& f) {
  if (pairsValid_ && skinBoxes_.size() == grown_.size()) {
    // The CPs out of their skin boxes (refit's test), then the CPs and yarns that left (in order).
    outside_.resize(grown_.size());
    // and the CPs a persistent crossing handed back (their pairs return).
    const bool renewing = renew_.size() == grown_.size();
    parallelFor(static_cast<Index>(grown_.size()), kParallelGrain, threads(), [&](Index e) {
      outside_[e] = leftSkin_[e] || (renewing && renew_[e]);
    });
    stats.renewed = std::count(outside_.begin(), outside_.end(), 1);
    if (stats.renewed == 0) return;
    if (broadPhase != BroadPhase::SweepAndPrune) {
      const bool byYarn = broadPhase == BroadPhase::YarnTree;
      const std::vector<std::uint8_t>& renew = byYarn ? dirtyYarn_ : outside_;
      const auto renewed = [&](Index e) { return renew[byYarn ? f.elemYarn[e] : e] != 0; };
      if (byYarn) {
        dirtyYarn_.assign(f.yarns.size(), 0);
        for (std::size_t e = 0; e < grown_.size(); ++e)
          if (outside_[e]) dirtyYarn_[f.elemYarn[e]] = 1;
      }
      parallelFor(static_cast<Index>(grown_.size()), kParallelGrain, threads(), [&](Index e) {
        if (renewed(e)) skinBoxes_[e] = skinBox(f, e);
      });
      // The pairs between two CPs kept (by fixed chunks on the threads, in order); merged with the
      // fresh ones (both sorted) on the threads.
      keepChunked(pairs_, keptPairs_, 8192, keptChunks_, threads(),
                  [&](const CPPair& q) { return !renewed(q.a) && !renewed(q.b); });
      if (byYarn) tree.collide(f, skinBoxes_, filter_, freshPairs_, &dirtyYarn_);
      else grid.collide(f, skinBoxes_, filter_, freshPairs_, &outside_);
      parallelMerge(keptPairs_, freshPairs_, pairs_, threads());
      pairsChanged_ = true;
      ++stats.broadPhases;
      ++stats.partialBroadPhases;
      return;
    }
  }
  stats.renewed = 0;
  skinBoxes_.resize(grown_.size());
  parallelFor(static_cast<Index>(grown_.size()), kParallelGrain, threads(), [&](Index e) { skinBoxes_[e] = skinBox(f, e); });
  if (broadPhase == BroadPhase::YarnTree) tree.collide(f, skinBoxes_, filter_, pairs_);
  else if (broadPhase == BroadPhase::Grid) grid.collide(f, skinBoxes_, filter_, pairs_);
  else sap.collide(f, skinBoxes_, filter_, pairs_);
  pairsValid_ = true;
  pairsChanged_ = true;
  ++stats.broadPhases;
}

void CollisionStage::candidatePairs(Fabric& f, BroadPhase which, std::vector<CPPair>& out) {
  const ThreadCountScope threadCount(params_.threads);
  refit(f, 0);
  // A grid of its own: the stage's holds the boxes of its broad phase (the tree refits to the boxes
  // it is given).
  if (which == BroadPhase::YarnTree) tree.collide(f, grown_, filter_, out);
  else if (which == BroadPhase::Grid) GridCollider().collide(f, grown_, filter_, out);
  else sap.collide(f, grown_, filter_, out);
}

}  // namespace woven
