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

void CollisionStage::refit(Fabric& f, Real dt) {
  horizon_ = dt;
  if (filter_.yarnExclude.size() != f.yarns.size())
    filter_.configure(f, params_.selfExclude,
                      params_.model == ContactModel::Gap ? semiAxes(1, params_.mcd, params_.rule).a : 1.0);
  updateSectionFrames(f, tangent_);
  refitBounds(f, tangent_, params_.rule, params_.margin, bounds_);
  // Each CP's broad-phase box grows by the farthest its nodes can drift in the step, and (gap model)
  // be moved by the position projection after it.
  grow_.resize(bounds_.size());
  const Real projected = projectionReach(dt);
  speed_.resize(bounds_.size());
  parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) {
    const Index i = f.elem0[e];
    speed_[e] = std::sqrt(std::max(f.vel[i].squaredNorm(), f.vel[i + 1].squaredNorm()));
    grow_[e] = dt * speed_[e] + projected;
  });
  // Each node's odometer, the path it has travelled between the passes (at least its displacement,
  // however it moved: drifts, projections, checks), and each CP's, its two nodes' sum: the narrow
  // phase's screen bounds how far a pair's axes have come since it last measured them.
  if (lastPos_.size() != f.pos.size()) lastPos_ = f.pos, travelled_.assign(f.pos.size(), 0.0);
  parallelFor(f.nNodes(), kParallelGrain, threads(), [&](Index k) {
    travelled_[k] += (f.pos[k] - lastPos_[k]).norm();
    lastPos_[k] = f.pos[k];
  });
  odometer_.resize(f.elem0.size());
  parallelFor(f.nElems(), kParallelGrain, threads(),
              [&](Index e) { odometer_[e] = travelled_[f.elem0[e]] + travelled_[f.elem0[e] + 1]; });
  // Model Gap: each CP's unit chord and its length, once for the four or so pairs that share it and
  // the crossings (the same expressions as pair by pair: same bits).
  if (params_.model == ContactModel::Gap) {
    chords_.unit.resize(f.nElems());
    chords_.length.resize(f.nElems());
    parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) {
      const Index i = f.elem0[e];
      const Vec3 d = f.pos[i + 1] - f.pos[i];
      chords_.unit[e] = d.normalized();
      chords_.length[e] = d.norm();
    });
  }
  growBoxes(bounds_, grow_, grown_);
}

namespace {
// Box a lies inside box b: on each of b's axes, a's projection lies within b's slab.
bool inside(const OBB& a, const OBB& b) {
  const Vec3 d = b.axes.transpose() * (a.centre - b.centre);
  const Mat3 c = (b.axes.transpose() * a.axes).cwiseAbs();
  return ((d.cwiseAbs() + c * a.extent).array() <= b.extent.array()).all();
}
}  // namespace

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
    // The containment test of every CP (threads), then the CPs and yarns that left (in order).
    outside_.resize(grown_.size());
    // and the CPs a persistent crossing handed back (their pairs return).
    const bool renewing = renew_.size() == grown_.size();
    parallelFor(static_cast<Index>(grown_.size()), kParallelGrain, threads(), [&](Index e) {
      outside_[e] = !inside(grown_[e], skinBoxes_[e]) || (renewing && renew_[e]);
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
      // The pairs between two CPs kept, by fixed chunks (threads) joined in order; merged with the
      // fresh ones (both sorted) on the threads.
      constexpr Index kChunk = 8192;
      const Index n = static_cast<Index>(pairs_.size());
      keptChunks_.resize(chunkCount(n, kChunk));
      parallelFor(static_cast<Index>(keptChunks_.size()), 2, threads(), [&](Index t) {
        std::vector<CPPair>& out = keptChunks_[t];
        out.clear();
        for (Index k = t * kChunk, end = std::min(n, k + kChunk); k < end; ++k)
          if (!renewed(pairs_[k].a) && !renewed(pairs_[k].b)) out.push_back(pairs_[k]);
      });
      joinChunks(keptChunks_, keptPairs_, threads());
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
