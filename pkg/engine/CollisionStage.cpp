#include "engine/CollisionStage.hpp"
#include "engine/StageUtil.hpp"
#include "core/Errors.hpp"
#include "core/Parallel.hpp"
#include <algorithm>
#include <array>
#include <chrono>
#include <type_traits>
#include <cmath>

namespace woven {

using namespace stage;  // engine/StageUtil.hpp

BroadPhase broadPhaseByName(const std::string& name) {
  if (name == "tree") return BroadPhase::YarnTree;
  if (name == "sap") return BroadPhase::SweepAndPrune;
  if (name == "grid") return BroadPhase::Grid;
  throw ParameterError("broad_phase", "'" + name + "'",
                       "'tree' (OBB tree per yarn), 'sap' (sweep and prune) or 'grid' (uniform grid of cells)");
}

CollisionStage::CollisionStage(const ContactParams& p, BroadPhase broad) : broadPhase(broad) { setParams(p); }

void CollisionStage::setParams(const ContactParams& p) {
  p.validate();
  params_ = p;
  pairsValid_ = false;
  invalidateCache();  // contacts measured with other parameters
  restFlat_.clear();
  filter_.selfExclude = p.selfExclude;
  filter_.yarnExclude.clear();  // configured again for the fabric at the next refit
}

void CollisionStage::invalidateCache() {
  cache_.clear(), memo_.clear(), cachePairs_.clear(), forgetHeld_ = true;
  // The crossings' pairs return to the general pipeline: a full broad phase lists them again.
  if (!crossings_.empty()) pairsValid_ = false;
  crossings_.reset(Fabric{});
}

bool CollisionStage::allowsSubsteps(const ContactParams& p) {
  return p.model == ContactModel::Gap && p.response != Response::Penalty && p.flattening != Flattening::Springs;
}

Real CollisionStage::beforeDrift(Fabric& f, Real dt, Real horizon) {
  if (horizon != dt && !allowsSubsteps(params_)) throw ParameterError("substeps", "more than 1", kSubstepsRange);
  const ThreadCountScope threadCount(params_.threads);
  auto t = Clock::now();
  for (const RigidBody& b : bodies) b.validate();
  const bool springs = params_.flattening == Flattening::Springs;
  const bool flattens = params_.flattening != Flattening::None;
  const bool penalty = params_.response == Response::Penalty;
  if (springs) restoreSections(f);
  againStale_ = true;  // new contacts: resolveAgain marks them afresh
  passMove_.assign(f.pos.size(), 0.0);
  refit(f, horizon);
  stats.seconds[0] += since(t);
  trackCrossings(f);
  if (params_.yarnContacts) broad(f);
  else pairs_.clear();
  stats.seconds[1] += since(t);
  if (params_.yarnContacts) narrow(f, horizon);
  else contacts_.clear();
  measureCrossings(f, horizon, true);
  narrowBodies(f, horizon);
  stats.seconds[2] += since(t);

  stats.candidates = static_cast<long>(pairs_.size());
  stats.contacts = static_cast<long>(contacts_.size());
  stats.flattened = 0;
  stats.flattenPasses = flattens ? flatten(f, params_.flattenPasses, horizon) : 0;
  checkOverlaps(f, dt);
  // The node travel the projection's first sweep bounds each gap by (PositionProjection): a check's
  // moves are not counted in it, so after one every contact is measured.
  passMoveValid_ = stats.check.pushed == 0;
  // Overlap after flattening and the check (what none of flattening, the last projection and the
  // check removed): its largest and mean values over the contacts in overlap, and sums for the
  // mean over time.
  // Per fixed chunk (threads): the deepest (the first of equals) and the moving count; the overlaps
  // listed and summed in contact order (the serial sum's bits).
  constexpr Index kChunk = 4096;
  const Index nc = static_cast<Index>(contacts_.size());
  overlapChunks_.resize(chunkCount(nc, kChunk));
  scanChunks_.resize(overlapChunks_.size());
  parallelFor(static_cast<Index>(overlapChunks_.size()), 2, threads(), [&](Index t) {
    OverlapScan& q = scanChunks_[t];
    q = OverlapScan{};
    overlapChunks_[t].clear();
    for (Index k = t * kChunk, end = std::min(nc, k + kChunk); k < end; ++k) {
      const CPContact& c = contacts_[k];
      if (-c.gap > q.deepest) q.deepest = -c.gap, q.at = k;
      if (c.gap < 0) overlapChunks_[t].push_back(c.gap);
      q.moving += c.time > 0;
    }
  });
  stats.penetration = 0;
  stats.deepestA = stats.deepestB = -1;
  stats.moving = 0;
  for (const OverlapScan& q : scanChunks_) {
    if (q.deepest > stats.penetration)
      stats.penetration = q.deepest, stats.deepestA = contacts_[q.at].cpA, stats.deepestB = contacts_[q.at].cpB;
    stats.moving += q.moving;
  }
  joinChunks(overlapChunks_, overlapGaps_, threads());
  Real sum = 0;
  for (const Real gap : overlapGaps_) sum -= gap;
  const long count = static_cast<long>(overlapGaps_.size());
  stats.meanPenetration = count > 0 ? sum / count : 0.0;
  stats.overlapping = count;
  stats.overlapSum += sum, stats.overlapCount += count;
  stats.impulses = ImpulseReport{};
  stats.correctionEnergy = 0;
  Real added = 0;
  if (!penalty) {
    law_.resolve(f, contacts_, capacityOf(f), dt, params_, stats.impulses, bodyContacts_, &bodies, horizon,
                 markRowable(horizon));
    if (!crossings_.empty()) {  // the crossings' impulses: the next step's warm start
      law_.contactImpulses(contacts_.size(), impulses_);
      crossings_.keepImpulses(contacts_, impulses_);
    }
    bodyWork_ += stats.impulses.bodyWork;
    frictionWork_ += stats.impulses.frictionWork;
    added += stats.impulses.energyChange;
  }
  // Force-based parts (law/NormalForces): penalty springs on the overlaps left after flattening,
  // and the section springs. Their spring energy goes to the spring book (springEnergy), so what is
  // returned is only what they dissipate and the bodies' work.
  forces_.clear();
  Real spring = 0;
  if (penalty) {
    const Real kp = params_.penaltyStiffness, zeta = params_.penaltyDamping;
    for (const CPContact& c : contacts_)
      if (c.time == 0 && c.gap < 0) forces_.addYarn(f, c, -kp * c.gap, kp, zeta), spring += 0.5 * kp * c.gap * c.gap;
    for (const BodyContact& c : bodyContacts_)
      if (c.time == 0 && c.gap < 0)
        forces_.addBody(f, c, bodies, -kp * c.gap, kp, zeta), spring += 0.5 * kp * c.gap * c.gap;
  }
  if (springs) spring += addSectionSprings(f);
  stats.forces = NormalForceReport{};
  if (forces_.size() > 0) {
    forces_.apply(f, &bodies, dt, stats.forces);
    bodyWork_ += stats.forces.bodyWork;
    added += stats.forces.bodyWork - stats.forces.dissipated;
  }
  stats.springEnergy = spring;
  spring_ = spring + stats.forces.halfDrift;
  stats.bodyContacts = static_cast<long>(bodyContacts_.size());
  stats.bodyPenetration = 0;
  stats.deepestBodyCP = -1;
  for (const BodyContact& c : bodyContacts_) {
    if (-c.gap > stats.bodyPenetration) stats.bodyPenetration = -c.gap, stats.deepestBodyCP = c.cp;
    if (c.gap < 0) stats.bodyOverlapSum -= c.gap, ++stats.bodyOverlapCount;
  }
  stats.maxBodyPenetration = std::max(stats.maxBodyPenetration, stats.bodyPenetration);
  if (!penalty && params_.model == ContactModel::Paper)
    stats.correctionEnergy = ImpulseLaw::correctPositions(f, contacts_, params_);
  stats.seconds[3] += since(t);

  ++stats.steps;
  stats.maxPenetration = std::max(stats.maxPenetration, stats.penetration);
  stats.maxUnresolved = std::max(stats.maxUnresolved, stats.impulses.unresolved);
  stats.maxResidual = std::max(stats.maxResidual, stats.impulses.residual);
  stats.totalRows += stats.impulses.rows, stats.totalSweeps += stats.impulses.iterations;
  stats.totalUnresolved += stats.impulses.unresolved;
  return added + stats.correctionEnergy;
}

// The check (PositionProjection, checkDepth): contacts left deeper than projection_check after the
// flattening passes seed a projection with no allowance, before the rows. The projection after the
// last drift left the flattening its allowance, measured then; the flattening took less where the
// measure changed under it (traced on broken pieces after perforation: a piece turning from crossing
// to side by side, its measure moving from the half-thickness to the width that flattening had just
// grown, 11.9 um left; a closest point moving onto a rounder section), and those overlaps met the
// rows, which hold them (room 0) but do not take them out.
void CollisionStage::checkOverlaps(Fabric& f, Real dt) {
  stats.check = ProjectionReport{};
  const int sweeps = params_.projectionSweepCount();
  const Real depth = params_.projectionCheck;
  if (sweeps <= 0 || depth < 0) return;
  // The deepest overlap, a maximum per fixed chunk (exact in any order).
  Real deepest = chunkedSum(static_cast<Index>(contacts_.size()), 4096, threads(), DeepestOf{}, [&](Index k0, Index k1) {
                   DeepestOf d;
                   for (Index k = k0; k < k1; ++k) d.value = std::max(d.value, -contacts_[k].gap);
                   return d;
                 }).value;
  for (const BodyContact& c : bodyContacts_) deepest = std::max(deepest, -c.gap);
  if (!(deepest > depth)) return;
  stats.maxChecked = std::max(stats.maxChecked, deepest);
  projector_.project(f, contacts_, bodyContacts_, bodies, capacityOf(f), sweeps, params_.projectionSlop,
                     params_.projectionMaxMove, params_.rule, dt, stats.check, params_.sweepOrder, depth);
  stats.checks += stats.check.pushed > 0;
  projectionEnergy_ += stats.check.energy;
  stats.projectionEnergy += stats.check.energy;
}

Real CollisionStage::resolveAgain(Fabric& f, Real dt, Real horizonLeft) {
  if (contacts_.empty() && bodyContacts_.empty()) return 0;
  const ThreadCountScope threadCount(params_.threads);
  auto t = Clock::now();
  const Index nc = static_cast<Index>(contacts_.size());
  const std::uint8_t* again = nullptr;  // the contacts solved again (null: all)
  if (!slowNode_.empty() && againStale_) {
    // Multi-rate springs: a contact whose four nodes are slow moved at constant velocity since the
    // pass unless an impulse reached it, so it is solved again only within two contacts of a fast
    // node or of a CP on a body (the impulses of the first ring move the second's nodes); beyond,
    // the projection takes what is left. The pass's contacts fix the set: marked once per pass.
    againStale_ = false;
    nearFast_.resize(f.nNodes());
    for (Index i = 0; i < f.nNodes(); ++i) nearFast_[i] = !slowNode_[i];
    for (const BodyContact& c : bodyContacts_) nearFast_[f.elem0[c.cp]] = nearFast_[f.elem0[c.cp] + 1] = 1;
    again_.resize(static_cast<std::size_t>(nc));
    Index node[kMaxStencil];
    Real w[kMaxStencil];
    for (int ring = 0; ring < 2; ++ring) {
      if (ring == 1)  // the first ring's nodes
        for (Index k = 0; k < nc; ++k)
          if (again_[k])
            for (int q = 0, n = contactStencil(f, contacts_[k], node, w); q < n; ++q) nearFast_[node[q]] = 1;
      for (Index k = 0; k < nc; ++k) {
        const int n = contactStencil(f, contacts_[k], node, w);
        again_[k] = std::any_of(node, node + n, [&](Index i) { return nearFast_[i] != 0; });
      }
    }
  }
  if (!slowNode_.empty()) again = again_.data();
  // A contact of a CP broken since the pass gets no push: infinite room (its row stays at 0).
  parallelFor(nc, 256, threads(), [&](Index k) {
    CPContact& c = contacts_[k];
    if (again && !again[k]) return;
    if (!f.alive[c.cpA] || !f.alive[c.cpB]) c.gap = INFINITY;
    else remeasure(f, c, params_.rule, false);
  });
  for (BodyContact& c : bodyContacts_) {
    if (!f.alive[c.cp]) c.gap = INFINITY;
    else remeasureBody(f, bodies[c.body], c);
  }
  // The rows of the pass's contacts that could close within its horizon (markRowable), of those
  // solved again.
  const std::uint8_t* rows = rowable_.size() == contacts_.size() && params_.model == ContactModel::Gap ? rowable_.data() : nullptr;
  if (rows && again) {
    rowAgain_.resize(contacts_.size());
    for (Index k = 0; k < nc; ++k) rowAgain_[k] = rows[k] & again[k];
    rows = rowAgain_.data();
  } else if (again) {
    rows = again;
  }
  ImpulseReport rep;
  law_.resolve(f, contacts_, capacityOf(f), dt, params_, rep, bodyContacts_, &bodies, horizonLeft, rows);
  bodyWork_ += rep.bodyWork;
  frictionWork_ += rep.frictionWork;
  stats.seconds[3] += since(t);
  return rep.energyChange;
}

// The contacts that can close their gap within the horizon get rows (model Gap; the paper's rows
// decide by their own test): gap <= margin + horizon x twice the fastest speed in the scene (a node
// or a body's surface). Not the contact's own nodes' speeds: the solve passes momentum on within
// the step (a projectile pushes a node into the next yarn), and a contact left without a row there
// closed in the drift, where the projection took it out without its impulse: the 3 mm sphere at
// 200 m/s lost 7 % less velocity at 0.35 dt_crit than at 0.7. The others are listed for the
// position projection alone (their reach includes what it may move: narrow), where a row would hold
// lambda = 0 through every sweep: the side-by-side neighbours of a tight weave, 30-80 um apart, were
// half the rows of the default impact.
const std::uint8_t* CollisionStage::markRowable(Real horizon) {
  if (params_.model != ContactModel::Gap) return nullptr;
  const Index nc = static_cast<Index>(contacts_.size());
  rowable_.resize(contacts_.size());
  Real fastest = chunkedSum(static_cast<Index>(speed_.size()), 4096, threads(), DeepestOf{}, [&](Index k0, Index k1) {
                   DeepestOf m;  // a maximum, per fixed chunk
                   for (Index k = k0; k < k1; ++k) m.value = std::max(m.value, speed_[k]);
                   return m;
                 }).value;
  for (const RigidBody& b : bodies) {
    Real reach = 0;  // the body's farthest surface point from its centre (bound)
    for (std::size_t k = 0; k < b.parts.size(); ++k) reach = std::max(reach, b.parts[k].offset.norm() + b.partReach(k));
    fastest = std::max(fastest, b.vel.norm() + b.angVel.norm() * reach);
  }
  const Real room = params_.margin + 2 * horizon * fastest;
  parallelFor(nc, kParallelGrain, threads(), [&](Index k) { rowable_[k] = contacts_[k].gap <= room; });
  return rowable_.data();
}

// The fastest node of CP e and its neighbours in its yarn (the nodes a curve on e reads) [m/s].
Real CollisionStage::fastestNear(const Fabric& f, Index e) const {
  const Yarn& y = f.yarns[f.elemYarn[e]];
  Real v = speed_[e];
  if (e > y.firstElem) v = std::max(v, speed_[e - 1]);
  if (e + 1 < y.firstElem + y.nElems) v = std::max(v, speed_[e + 1]);
  return v;
}

Real CollisionStage::afterDrift(Fabric& f, Real dt, bool restitute, bool project) {
  const ThreadCountScope threadCount(params_.threads);
  // The nodes' travel since the pass measured its contacts (each substep's drift, before the
  // restitution pass changes the velocities it drifted with).
  if (passMove_.size() == f.pos.size())
    parallelFor(f.nNodes(), kParallelGrain, threads(), [&](Index k) { passMove_[k] += dt * f.vel[k].norm(); });
  for (RigidBody& b : bodies) {
    b.pos += dt * b.vel;
    const Real angle = b.angVel.norm() * dt;  // YADE's rotation of a spherical body over the step
    if (angle > 0) b.ori = (Quat(Eigen::AngleAxis<Real>(angle, b.angVel.normalized())) * b.ori).normalized();
  }
  if (params_.response == Response::Penalty) return 0;
  const Real dE = restitute ? law_.restitute(f, params_, &bodies, &bodyWork_) : 0.0;
  stats.impulses.energyChange += dE;
  if (!project) return dE;
  stats.projection = ProjectionReport{};
  if (const int sweeps = params_.projectionSweepCount(); sweeps > 0) {
    auto t = Clock::now();
    projector_.project(f, contacts_, bodyContacts_, bodies, capacityOf(f), sweeps, params_.projectionSlop,
                       params_.projectionMaxMove, params_.rule, dt, stats.projection, params_.sweepOrder, -1,
                       passMoveValid_ && passMove_.size() == f.pos.size() ? passMove_.data() : nullptr);
    projectionEnergy_ += stats.projection.energy;
    stats.projectionEnergy += stats.projection.energy;
    stats.seconds[4] += since(t);
  }
  return dE;
}

Real CollisionStage::settle(Fabric& f, int maxPasses) {
  const ThreadCountScope threadCount(params_.threads);
  Real left = 0;
  for (int outer = 0; outer < maxPasses; ++outer) {
    pairsValid_ = false;
    refit(f, 0);
    broad(f);
    narrow(f, 0);
    const int passes = flatten(f, maxPasses);
    left = 0;
    for (const CPContact& c : contacts_) left = std::max(left, -c.gap);
    if (passes == 0) break;
  }
  return left;
}

Real CollisionStage::overlap(Fabric& f) {
  // A query: measured by a copy of the stage (its pairs, contacts and contact cache stay the ones
  // the next step expects), and the section frames refit turns are put back, so that asking
  // changes nothing (it moved the trajectory by 2e-17 m per call).
  const Vec3Array dirs = f.secDir;
  CollisionStage probe(*this);
  const ThreadCountScope threadCount(params_.threads);
  probe.pairsValid_ = false;
  probe.refit(f, 0);
  probe.broad(f);
  probe.narrow(f, 0);
  probe.measureCrossings(f, 0, false);
  Real worst = 0;
  for (const CPContact& c : probe.contacts_) worst = std::max(worst, -c.gap);
  f.secDir = dirs;
  return worst;
}

}  // namespace woven
