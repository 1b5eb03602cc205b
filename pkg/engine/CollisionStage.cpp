#include "engine/CollisionStage.hpp"
#include "bound/CPBound.hpp"
#include "core/Errors.hpp"
#include "core/Parallel.hpp"
#include "geom/GapFunction.hpp"
#include "geom/SegmentDistance.hpp"
#include "geom/SeparatingAxis.hpp"
#include "law/SectionFlattening.hpp"
#include <algorithm>
#include <array>
#include <chrono>
#include <type_traits>
#include <cmath>

namespace woven {

namespace {
using Clock = std::chrono::steady_clock;
inline double since(Clock::time_point& t) {
  const auto now = Clock::now();
  const double s = std::chrono::duration<double>(now - t).count();
  t = now;
  return s;
}
// Both end sections at the MCD: the CP's flattening capacity is 0 along any normal (its reach at the
// MCD is its reach now), so the capacity need not be computed.
inline bool lockedCP(const Fabric& f, Index e, Real mcd) {
  return f.secFlat[f.elem0[e]] >= mcd && f.secFlat[f.elem0[e] + 1] >= mcd;
}
// A maximum carried as a sum (chunkedSum): the largest of the chunks' largest, exact in any order.
struct DeepestOf {
  Real value = 0;
  DeepestOf& operator+=(const DeepestOf& o) { return value = std::max(value, o.value), *this; }
};
// A body contact's key: its CP, body, part and end (BodyContact::end; -1: the sphere's own place,
// or a box or cylinder contact). Only a contact of the same key is its memory: a sphere's contact
// held at an end node measures that node's section, not the section at the centre's place.
inline std::uint64_t bodyKey(Index cp, int body, int part, int end) {
  return (static_cast<std::uint64_t>(cp) << 32) | (static_cast<std::uint64_t>(body & 0x3fff) << 18) |
         (static_cast<std::uint64_t>(part & 0xffff) << 2) | static_cast<std::uint64_t>(end + 1);
}
}  // namespace

// What flattening can still take along a contact's normal (both CPs) [m]: the impulse rows' room
// beyond the gap, and the overlap the position projection leaves to the next flattening passes.
std::function<Real(const CPContact&)> CollisionStage::capacityOf(const Fabric& f) const {
  return [this, &f](const CPContact& c) {
    if (params_.flattening == Flattening::None || (lockedCP(f, c.cpA, params_.mcd) && lockedCP(f, c.cpB, params_.mcd)))
      return Real(0);
    // Sections the measure memory holds (capMeasure) are not counted on to flatten: they give only
    // past what the cap holds, and that grows as the pieces move within the step (a CP end sliding
    // over a yarn at 1000 m/s: 16 um in one step, and 14 um of overlap the projection had left to
    // a flattening that could not take it).
    if (c.hHeld > 0) return Real(0);
    return capacityOne(f, c, false) + capacityOne(f, c, true);
  };
}

// One side's flattening capacity along the contact: the paper's extent of the CP (model Paper), or
// the support at the contact point (model Gap; B's side seen along -n).
Real CollisionStage::capacityOne(const Fabric& f, const CPContact& c, bool sideB, const std::vector<Real>* flat) const {
  const Index e = sideB ? c.cpB : c.cpA;
  if (c.kind == ContactKind::Paper) return flatteningCapacity(f, tangent_, e, c.normal, params_, flat);
  return flatteningCapacityAt(f, tangent_, e, sideB ? c.sB : c.sA, sideB ? Vec3(-c.hDir) : c.hDir,
                              measuresThickness(f, c), params_, flat);
}

// A gap contact whose measure is mostly the half-thickness (a persistent crossing; pieces crossing
// at more than 32.5 degrees, half way through the blend of GapFunction's thicknessWeight): it
// flattens b itself.
bool CollisionStage::measuresThickness(const Fabric& f, const CPContact& c) const {
  return c.kind == ContactKind::Crossing || (c.kind == ContactKind::Cross && crossesSteeply(f, c));
}
bool CollisionStage::crossesSteeply(const Fabric& f, const CPContact& c) const {
  if (f.elemYarn[c.cpA] == f.elemYarn[c.cpB]) return true;  // a fold: face to face (GapFunction)
  const Vec3 tA = (f.pos[f.elem0[c.cpA] + 1] - f.pos[f.elem0[c.cpA]]).normalized();
  const Vec3 tB = (f.pos[f.elem0[c.cpB] + 1] - f.pos[f.elem0[c.cpB]]).normalized();
  return std::abs(tA.dot(tB)) < 0.84339144581288572;  // cos 32.5 degrees
}

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

// The candidate pairs of the last broad phase hold as long as every CP's box stays inside the box
// that phase used (its box then, grown by the skin): a pair whose boxes overlap now overlapped then.
// Only the CPs out of their skin boxes (the grid), or the yarns that hold one (the OBB tree), are
// collided again, their skin boxes renewed: the pairs between two that stayed inside still hold.
// Under the default impact that is 2-45 % of the ply's CPs, where a full phase took them all at 128
// of 150 steps. The contacts are the same as with a full broad phase: the narrow phase decides each
// pair on its own, and a pair it does not measure forgets its memory as one the broad phase did not
// list.
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
      for (Index e = 0; e < static_cast<Index>(grown_.size()); ++e)
        if (renewed(e)) skinBoxes_[e] = skinBox(f, e);
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
  for (Index e = 0; e < static_cast<Index>(grown_.size()); ++e) skinBoxes_[e] = skinBox(f, e);
  if (broadPhase == BroadPhase::YarnTree) tree.collide(f, skinBoxes_, filter_, pairs_);
  else if (broadPhase == BroadPhase::Grid) grid.collide(f, skinBoxes_, filter_, pairs_);
  else sap.collide(f, skinBoxes_, filter_, pairs_);
  pairsValid_ = true;
  pairsChanged_ = true;
  ++stats.broadPhases;
}

// Each pair's last static contact is kept with its four node positions. While the CP sections are
// unchanged and the four nodes have moved together to within cacheDistance (a translation of the
// pair changes no gap), the contact is carried along instead of tested again: its gap changes by the
// relative displacement of the two contact points along the normal (exact for any translation of
// either CP; the turn of the normal that the small relative motion allows is neglected: at most
// cacheDistance over the CP length, times the CP's size).
bool CollisionStage::reuse(const Fabric& f, std::size_t k, CPContact& c) const {
  const PairCache& pc = cache_[k];
  if (!pc.valid || sectionStamp_[pc.contact.cpA] >= pc.clock || sectionStamp_[pc.contact.cpB] >= pc.clock) return false;
  const Index i = f.elem0[pc.contact.cpA], j = f.elem0[pc.contact.cpB];
  const Vec3 d0 = f.pos[i] - pc.x[0], d1 = f.pos[i + 1] - pc.x[1], d2 = f.pos[j] - pc.x[2], d3 = f.pos[j + 1] - pc.x[3];
  const Real lim = params_.cacheDistance * params_.cacheDistance;
  if ((d1 - d0).squaredNorm() > lim || (d2 - d0).squaredNorm() > lim || (d3 - d0).squaredNorm() > lim) return false;
  c = pc.contact;
  const Vec3 dA = (1 - c.sA) * d0 + c.sA * d1, dB = (1 - c.sB) * d2 + c.sB * d3;
  const Real dn = c.normal.dot(dB - dA);
  c.gap += dn;
  c.boxDepth -= dn;
  c.point += 0.5 * (dA + dB);
  return true;
}

// After a broad phase the cache (model Paper) or the memory (model Gap) follows its pairs (both
// lists sorted): a pair kept keeps its entry. Only the one in use is kept: the contact cache entry
// is ten times the memory's size, and copying it for every pair was a share of the gap model's
// narrow phase.
void CollisionStage::remapCache(bool caching, bool gapModel) {
  const auto follow = [&](auto& now, auto& old, bool used) {
    using Entry = typename std::decay_t<decltype(now)>::value_type;
    old.swap(now);
    now.resize(used ? pairs_.size() : 0);  // each entry written once below
    if (!used) return;
    // Fixed chunks of the new pairs, each starting its walk where the old list reaches its first
    // pair (the serial walk's place there): the same entries for any thread count.
    constexpr Index kChunk = 4096;
    const Index n = static_cast<Index>(pairs_.size());
    parallelFor(chunkCount(n, kChunk), 2, threads(), [&](Index t) {
      const Index k0 = t * kChunk, k1 = std::min(n, k0 + kChunk);
      std::size_t o = static_cast<std::size_t>(
          std::lower_bound(cachePairs_.begin(), cachePairs_.end(), pairs_[k0]) - cachePairs_.begin());
      for (Index k = k0; k < k1; ++k) {
        while (o < cachePairs_.size() && cachePairs_[o] < pairs_[k]) ++o;
        now[k] = o < cachePairs_.size() && cachePairs_[o] == pairs_[k] && o < old.size() ? old[o] : Entry();
      }
    });
  };
  follow(cache_, cacheOld_, caching);
  follow(memo_, memoOld_, gapModel);
  cachePairs_ = pairs_;
}

void CollisionStage::narrow(const Fabric& f, Real dt) {
  ++cacheClock_;
  if (sectionStamp_.size() != f.elem0.size()) sectionStamp_.assign(f.elem0.size(), 0);
  // Section springs reset every section each step (restoreSections): no contact outlives its sections.
  const bool caching = params_.cacheDistance > 0 && params_.flattening != Flattening::Springs &&
                       params_.model == ContactModel::Paper;
  const bool gapModel = params_.model == ContactModel::Gap;
  if (cachePairs_.size() != pairs_.size() || pairsChanged_ || cache_.size() != (caching ? pairs_.size() : 0) ||
      memo_.size() != (gapModel ? pairs_.size() : 0))
    remapCache(caching, gapModel);
  pairsChanged_ = false;
  if (gapModel) seedReturned(f);
  if (gapModel) {
    // Each node's major semi-axis [m], and each CP's largest at the MCD (the screen's). The speeds,
    // the CPs' chords and odometers are refit's (every narrow phase follows a refit, with the same
    // positions and velocities).
    widest_.resize(f.secRadius.size());
    parallelFor(f.nNodes(), kParallelGrain, threads(),
                [&](Index k) { widest_[k] = semiAxes(f.secRadius[k], f.secFlat[k], params_.rule).a; });
    widestAtMcd_.resize(f.elem0.size());
    parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) {
      const Index i = f.elem0[e];
      widestAtMcd_[e] = semiAxes(std::max(f.secRadius[i], f.secRadius[i + 1]), params_.mcd, params_.rule).a;
    });
  }
  // Pairs the position projection may move together (each node at most kProjectionTravel x
  // projectionMaxMove) are listed too.
  const Real projected = projectionReach(dt);
  // Fixed chunks of the sorted pairs (threads take them in any order), concatenated in chunk order:
  // the same contacts in the same order for any thread count (each pair's cache entry is its own).
  constexpr Index kPairChunk = 512;
  const Index n = static_cast<Index>(pairs_.size());
  const Index chunks = chunkCount(n, kPairChunk);
  slices_.resize(chunks);
  reused_.assign(chunks, 0);
  parallelForDynamic(chunks, 4, threads(), [&](Index t) {
    std::vector<CPContact>& out = slices_[t];
    out.clear();
    CPContact c;
    for (Index k = t * kPairChunk, end = std::min(n, k + kPairChunk); k < end; ++k) {
      const CPPair& pr = pairs_[k];
      if (!f.alive[pr.a] || !f.alive[pr.b]) continue;  // broken since the broad phase
      if (caching && reuse(f, k, c)) {
        out.push_back(c);
        ++reused_[t];
        continue;
      }
      if (caching) cache_[k].valid = false;
      if (gapModel) {
        PairMemo& pc = memo_[k];
        // The pair's gap functions; listed when they can close within the step (speculative
        // contacts: the row lets each close exactly its gap), bounded by the node speeds.
        const Index i = f.elem0[pr.a], j = f.elem0[pr.b];
        const Real reach = params_.margin + 2 * projected + dt * (speed_[pr.a] + speed_[pr.b]);
        // The screen: the pair's clearance beyond the widest sections the MCD allows, as last
        // evaluated, less what its CPs' nodes have travelled since (the axes' distance moves by no
        // more), still beyond the reach: the test below would skip it (its widest sections are no
        // wider), so it is skipped unmeasured, with the same outcome (the neighbours of a tight
        // weave lie 30-80 um apart, and most of a ply moves far less than that in a step).
        if (pc.clear - (odometer_[pr.a] + odometer_[pr.b] - pc.odometer) > reach) {
          if (pc.memo) pc.forget();
          continue;
        }
        // No section reaches beyond its major semi-axis: pairs whose axes are farther apart than
        // that cannot be listed (most pairs of a broad phase with a skin), and need no sections;
        // nor can pairs whose boxes grown by the step's motion do not meet. A pair that fails either
        // is not measured, and its measure is forgotten (the sections may turn unseen while apart).
        // The segments first: a few dot products, where the boxes' separating-axis test took 13 % of
        // the default impact.
        const Real widest = std::max(std::max(widest_[i], widest_[i + 1]), std::max(widest_[j], widest_[j + 1]));
        const SegmentClosest axes = closestSegmentSegment(f.pos[i], f.pos[i + 1], f.pos[j], f.pos[j + 1]);
        pc.clear = axes.distance - widestAtMcd_[pr.a] - widestAtMcd_[pr.b];
        pc.odometer = odometer_[pr.a] + odometer_[pr.b];
        // The boxes' test probed first at the point between the axes (a crossing's midpoint lies
        // inside both sections).
        if (axes.distance > 2 * widest + reach ||
            !obbOverlap(grown_[pr.a], grown_[pr.b],
                        closestMidpoint(f.pos[i], f.pos[i + 1], f.pos[j], f.pos[j + 1], axes))) {
          if (pc.memo) pc.forget();  // as a pair the broad phase no longer lists: the contacts do not depend on its skin
          continue;
        }
        bool side = sideBySide(f, pr.a, pr.b, pc.memo && pc.side, &chords_);
        CPContact two[2];
        // The pair's memory (GapFunction.hpp): its normals by point (a side-by-side pair's two
        // points are the ends of the shared part; one point that becomes two starts both from it,
        // two that become one from the first), its sections' measure at the nearest remembered
        // point. A point without a remembered measure (a pair new to the broad phase, or whose boxes
        // parted since, or a point far from the last ones) may claim no more than its
        // half-thicknesses where that overlaps: its sections are taken as turned the way that fits,
        // as a remembered pair's would have turned.
        const Vec3 orient[2] = {pc.memoNormal[0], pc.memoNormal[pc.memoPoints == 2 ? 1 : 0]};
        const int m = pairGaps(f, pr.a, pr.b, side, params_.rule, pc.memo ? orient : nullptr, two, &tangent_, &axes,
                             &chords_);
        // A point's memory is the last step's point nearest to it along the two axes, if that lay
        // within a quarter of the two sections' radii (67 um in KM2 706, about half the yarn
        // thickness): the same material places. A side-by-side end that passed from B's end to A's
        // moved 90 um along B, where the axes ran 60 um closer. (Matching anchors as well, so that
        // an end of a crumpled piece 60 um long did not take the other end's measure, was worse
        // over six 1000 m/s impacts: largest overlaps 0.068-0.199 thickness against 0.044-0.123.)
        const Real lenA = chords_.length[pr.a], lenB = chords_.length[pr.b];
        const Real reachMemo = 0.25 * (f.secRadius[i] + f.secRadius[j]);
        for (int q = 0; q < m; ++q) {
          Real remembered = NAN, nearest = reachMemo;
          for (int p = 0; p < pc.memoPoints; ++p) {
            const Real apart = std::abs(pc.memoS[p] - two[q].sA) * lenA + std::abs(pc.memoT[p] - two[q].sB) * lenB;
            if (apart <= nearest) nearest = apart, remembered = pc.memoMeasure[p];
          }
          if (std::isnan(remembered))
            remembered = pc.held ? 0.0
                                 : semiAxesAt(f, pr.a, two[q].sA, params_.rule).b + semiAxesAt(f, pr.b, two[q].sB, params_.rule).b;
          capMeasure(two[q], remembered);
        }
        pc.memo = true, pc.side = side, pc.memoPoints = m, pc.held = false;
        for (int q = 0; q < m; ++q)
          pc.memoS[q] = two[q].sA, pc.memoT[q] = two[q].sB, pc.memoNormal[q] = two[q].normal,
          pc.memoMeasure[q] = two[q].hA + two[q].hB;
        for (int q = 0; q < m; ++q)
          if (two[q].gap <= reach) out.push_back(two[q]);
        continue;
      }
      // The bounds lie inside the boxes grown by the step's motion: where those do not meet, the
      // pair neither touches nor meets within the step (a yes/no SAT with early out, cheaper than
      // the static test's depth and far cheaper than the moving test's four sweeps).
      if (!obbOverlap(grown_[pr.a], grown_[pr.b])) continue;
      if (cpContactStatic(f, bounds_, pr.a, pr.b, params_.margin, params_.rule, c)) {
        out.push_back(c);
        if (caching) {
          PairCache& pc = cache_[k];
          pc.valid = true, pc.contact = c, pc.clock = cacheClock_;
          const Index i = f.elem0[pr.a], j = f.elem0[pr.b];
          pc.x[0] = f.pos[i], pc.x[1] = f.pos[i + 1], pc.x[2] = f.pos[j], pc.x[3] = f.pos[j + 1];
        }
        continue;
      }
      if (dt > 0 && cpContactMoving(f, bounds_, pr.a, pr.b, dt, params_.margin, c))
        out.push_back(c);
    }
  });
  joinChunks(slices_, contacts_, threads());
  stats.cached = 0;
  for (Index t = 0; t < chunks; ++t) stats.cached += reused_[t];
}

void CollisionStage::narrowBodies(const Fabric& f, Real dt) {
  // The last step's contacts, by CP, body and part: the gap model's measure memory (bodyGap).
  heldBody_.swap(bodyContacts_);
  if (heldFor_ != bodies.size() || forgetHeld_) heldBody_.clear();  // bodies added or removed: indices moved
  heldFor_ = bodies.size(), forgetHeld_ = false;
  heldKeys_.clear();
  for (std::size_t q = 0; q < heldBody_.size(); ++q)
    heldKeys_.emplace_back(bodyKey(heldBody_[q].cp, heldBody_[q].body, heldBody_[q].part, heldBody_[q].end), q);
  std::sort(heldKeys_.begin(), heldKeys_.end());
  bodyContacts_.clear();
  bodyPairs_.clear();
  if (bodies.empty()) return;
  bodyCollider.collide(f, grown_, grow_, bodies, dt, bodyPairs_);
  measureBodies(f, dt);
}

// The body contacts of the candidates (bodyPairs_) with the sections as they stand, each with the
// last step's contact of its CP, body and part (heldBody_; a sphere's at the centre's place, not an
// end node's) as its measure memory.
void CollisionStage::measureBodies(const Fabric& f, Real dt) {
  bodyContacts_.clear();
  BodyContact c[2];
  const bool gapModel = params_.model == ContactModel::Gap;
  // The position projection may move a node by this much after the drift (toward the body, pushed
  // by its other contacts): such contacts are listed too, as the CP pairs are (narrow).
  const Real projected = projectionReach(dt);
  for (const BodyCandidate& pc : bodyPairs_) {
    const BodyContact* held = nullptr;
    if (gapModel) {
      const auto it = std::lower_bound(heldKeys_.begin(), heldKeys_.end(),
                                       std::make_pair(bodyKey(pc.cp, pc.body, pc.part, -1), std::size_t(0)));
      if (it != heldKeys_.end() && it->first == bodyKey(pc.cp, pc.body, pc.part, -1)) held = &heldBody_[it->second];
    }
    const int m = gapModel ? bodyGap(f, pc.cp, bodies[pc.body], pc.part, dt, params_.margin + projected, params_.rule, c,
                                     &tangent_, held)
                           : cpBodyContact(f, bounds_[pc.cp], pc.cp, bodies[pc.body], pc.part, dt, params_.margin,
                                           params_.rule, c[0]);
    for (int q = 0; q < m; ++q) {
      c[q].body = pc.body;
      bodyContacts_.push_back(c[q]);
    }
  }
}

// Paper Sec. 5.1 steps 1-3: take up each overlap by flattening the sections of both CPs (half each,
// the rest by the other when one is locked), re-test the contacts whose CPs changed, repeat.
int CollisionStage::flatten(Fabric& f, int maxPasses, Real bodyDt) {
  const Real tiny = 1e-15;  // [m]
  int passes = 0;
  for (; passes < maxPasses; ++passes) {
    flatBefore_ = f.secFlat;
    dirSum_.resize(f.pos.size(), Vec3::Zero());
    dirty_.assign(f.elem0.size(), 0);
    bool any = false;
    // The capacities are measured for every contact at once (threads), then the contacts flatten in
    // order. A capacity reads the snapshot flatBefore_, except that flatteningDirection lets a node that
    // is still circular (secFlat 0) turn freely: a node circular at the pass start and flattened by an
    // earlier contact of this pass changes that, so those CPs are measured again in the loop (the
    // serial order's result, the same bits at any thread count).
    // The contacts that can flatten (overlapping, not both locked at the pass start: capacity 0
    // leaves them to the impulses) listed by fixed chunks, in order.
    const Index nc = static_cast<Index>(contacts_.size());
    capacity_.resize(2 * contacts_.size());
    constexpr Index kChunk = 4096;
    flattenChunks_.resize(chunkCount(nc, kChunk));
    parallelFor(static_cast<Index>(flattenChunks_.size()), 2, threads(), [&](Index t) {
      std::vector<Index>& mine = flattenChunks_[t];
      mine.clear();
      for (Index k = t * kChunk, end = std::min(nc, k + kChunk); k < end; ++k) {
        const CPContact& c = contacts_[k];
        if (c.time > 0 || !(c.gap < -tiny)) continue;
        if (lockedCP(f, c.cpA, params_.mcd) && lockedCP(f, c.cpB, params_.mcd)) continue;
        capacity_[2 * k] = capacityOne(f, c, false, &flatBefore_);
        capacity_[2 * k + 1] = capacityOne(f, c, true, &flatBefore_);
        mine.push_back(k);
      }
    });
    joinChunks(flattenChunks_, flattenList_, threads());
    for (const Index k : flattenList_) {
      const CPContact& c = contacts_[k];
      // locked since the pass started, by an earlier contact of this loop
      if (lockedCP(f, c.cpA, params_.mcd) && lockedCP(f, c.cpB, params_.mcd)) continue;  // capacity 0: left to the impulses
      const Real need = c.hHeld - c.gap;  // the capped measure gives only past what the cap holds
      const auto turnedThisPass = [&](Index e) {
        const Index i = f.elem0[e];
        return (flatBefore_[i] == 0 && f.secFlat[i] != 0) || (flatBefore_[i + 1] == 0 && f.secFlat[i + 1] != 0);
      };
      const Real capA = turnedThisPass(c.cpA) ? capacityOne(f, c, false, &flatBefore_) : capacity_[2 * k];
      const Real capB = turnedThisPass(c.cpB) ? capacityOne(f, c, true, &flatBefore_) : capacity_[2 * k + 1];
      if (capA + capB <= tiny) continue;  // locked: left to the impulses
      Real dA = std::min(capA, 0.5 * need);
      const Real dB = std::min(capB, need - dA);
      dA = std::min(capA, need - dB);
      if (c.kind == ContactKind::Paper) {
        flattenCP(f, tangent_, c.cpA, c.normal, dA, params_, flatBefore_, dirSum_);
        flattenCP(f, tangent_, c.cpB, c.normal, dB, params_, flatBefore_, dirSum_);
      } else {  // the gap model measures at the contact point: flatten there
        const bool thickness = measuresThickness(f, c);
        flattenAt(f, tangent_, c.cpA, c.sA, c.hDir, thickness, dA, params_, flatBefore_, dirSum_);
        flattenAt(f, tangent_, c.cpB, c.sB, Vec3(-c.hDir), thickness, dB, params_, flatBefore_, dirSum_);
      }
      for (Index e : {c.cpA, c.cpB})
        for (Index q = std::max(e - 1, 0); q <= std::min(e + 1, f.nElems() - 1); ++q)
          if (f.elemYarn[q] == f.elemYarn[e]) dirty_[q] = 1;
      ++stats.flattened;
      any = true;
    }
    // The body contacts (model Gap, within a step): the paper's response (Sec. 5.1 steps 1-3) holds
    // for any two colliding OBBs, the projectile's among them. A body flattens nothing; the CP's
    // sections at the contact take up the overlap (and what the measure memory holds back) along the
    // normal, up to the MCD. Without it, at 4 CPs per span a sphere reaching a node between two
    // crossings, still round (2.4 times the flattened half-thickness), sat 15 um inside it.
    bool bodyFlattened = false;
    if (bodyDt >= 0 && params_.model == ContactModel::Gap && params_.flattening == Flattening::Geometric)
      for (const BodyContact& c : bodyContacts_) {
        if (!(c.gap < -tiny) || lockedCP(f, c.cp, params_.mcd)) continue;
        const Real cap = flatteningCapacityAt(f, tangent_, c.cp, c.s, c.normal, false, params_, &flatBefore_);
        if (cap <= tiny) continue;
        flattenAt(f, tangent_, c.cp, c.s, c.normal, false, c.held - c.gap, params_, flatBefore_, dirSum_);
        for (Index q = std::max(c.cp - 1, 0); q <= std::min(c.cp + 1, f.nElems() - 1); ++q)
          if (f.elemYarn[q] == f.elemYarn[c.cp]) dirty_[q] = 1;
        ++stats.flattened;
        any = bodyFlattened = true;
      }
    if (!any) break;
    turnSections(f, tangent_, flatBefore_, dirSum_);
    if (sectionStamp_.size() != f.elem0.size()) sectionStamp_.assign(f.elem0.size(), 0);
    parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) {
      if (dirty_[e]) {
        bounds_[e] = cpBound(f, tangent_, e, params_.rule, params_.margin);
        sectionStamp_[e] = cacheClock_;  // the cached contacts of this CP no longer hold
      }
    });
    parallelFor(nc, 256, threads(), [&](Index k) {  // each contact on its own
      CPContact& c = contacts_[k];
      if (c.time > 0 || !(dirty_[c.cpA] || dirty_[c.cpB])) return;
      if (c.kind != ContactKind::Paper) return remeasure(f, c, params_.rule, true, &tangent_);  // same points, new sections
      CPContact again;
      if (cpContactStatic(f, bounds_, c.cpA, c.cpB, params_.margin, params_.rule, again)) c = again;
      else c.gap = 2 * params_.margin;  // apart now: at least this far
    });
    if (bodyFlattened) measureBodies(f, bodyDt);  // the flattened sections, the same memory
  }
  return passes;
}

// Flattening Springs: the sections are elastic (paper Eq. 7: a spring between the axis node and the
// ellipse node). Each step they start from their shape at the first step (a built weave's settled
// sections) and flatten again, geometrically up to the MCD, as far as this step's overlaps ask;
// the deformation beyond the rest shape then pushes back (addSectionSprings). So the section's
// flattening is a function of the positions and its spring energy is a potential.
void CollisionStage::restoreSections(Fabric& f) {
  if (restFlat_.size() != f.secFlat.size()) restFlat_ = f.secFlat, restDir_ = f.secDir;
  f.secFlat = restFlat_;
  f.secDir = restDir_;
}

// The paper's Eq. 7, F_i = k_i (u_i^2 - u_i^1), is a spring between node i's axis position u^1 and
// its ellipse node u^2; here |u^2 - u^1| - r0 is the flattening r0 eps (beyond the rest shape) and
// k_i = k_s, so node k pushes back with k_s r0 eps_k along its flattening direction. The force
// reaches the yarns through the contacts pressing the node: node k's force is shared among its
// contacts in touch in proportion to its weight |w| in each (the impulse weights), and a contact
// gets half the sum over its four nodes (the A side and the B side carry the same force, springs in
// series). One contact in the middle of two CPs overlapping by delta: each node flattens by
// delta/2, the contact force is 2 x k_s delta/2 = k_s delta, the derivative of the energy
// 4 x 1/2 k_s (delta/2)^2. The flattening cosine (dir.n, 1 for a square crossing) is neglected.
// Returns the energy 1/2 k_s (r0 eps)^2 of the flattened sections [J].
Real CollisionStage::addSectionSprings(const Fabric& f) {
  const Real ks = params_.sectionStiffness, touch = 2 * params_.margin + 1e-12;
  nodeWeight_.assign(f.secFlat.size(), 0);
  auto nodesOf = [&](const CPContact& c, Index* node, Real* w) {
    node[0] = f.elem0[c.cpA], node[1] = node[0] + 1, node[2] = f.elem0[c.cpB], node[3] = node[2] + 1;
    w[0] = 1 - c.sA, w[1] = c.sA, w[2] = 1 - c.sB, w[3] = c.sB;
  };
  Index node[4];
  Real w[4];
  for (const CPContact& c : contacts_) {
    if (c.time > 0 || c.gap > touch) continue;
    nodesOf(c, node, w);
    for (int q = 0; q < 4; ++q) nodeWeight_[node[q]] += w[q];
  }
  for (const CPContact& c : contacts_) {
    if (c.time > 0 || c.gap > touch) continue;
    nodesOf(c, node, w);
    Real F = 0;
    for (int q = 0; q < 4; ++q) {
      const Index k = node[q];
      const Real d = f.secRadius[k] * (f.secFlat[k] - restFlat_[k]);
      if (d > 0 && nodeWeight_[k] > 0) F += 0.5 * ks * d * w[q] / nodeWeight_[k];
    }
    if (F > 0) forces_.addYarn(f, c, F, ks, 0);
  }
  Real energy = 0;
  for (std::size_t k = 0; k < restFlat_.size(); ++k) {
    const Real d = f.secRadius[k] * (f.secFlat[k] - restFlat_[k]);
    if (d > 0) energy += 0.5 * ks * d * d;
  }
  return energy;
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
    for (const RigidPart& q : b.parts)
      reach = std::max(reach, q.offset.norm() + std::max({q.halfSize.norm(), std::hypot(q.radius, q.halfLength)}));
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

Real CollisionStage::bodyOverlap(Fabric& f, int k) {
  // A query: refit turns the section frames to the current tangents, which changes the next step's
  // frames (they follow their previous direction): put them back so that asking changes nothing.
  const Vec3Array dirs = f.secDir;
  const ThreadCountScope threadCount(params_.threads);
  refit(f, 0);
  const RigidBody& b = bodies.at(k);
  Real worst = -INFINITY;
  BodyContact c[2];
  for (std::size_t part = 0; part < b.parts.size(); ++part)
    for (Index e = 0; e < f.nElems(); ++e) {
      if (!f.alive[e]) continue;
      const int m = params_.model == ContactModel::Gap
                        ? bodyGap(f, e, b, static_cast<int>(part), 0, params_.margin, params_.rule, c)
                        : cpBodyContact(f, bounds_[e], e, b, static_cast<int>(part), 0, params_.margin, params_.rule, c[0]);
      for (int q = 0; q < m; ++q) worst = std::max(worst, -c[q].gap);
    }
  f.secDir = dirs;
  return worst;
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
