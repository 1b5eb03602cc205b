// The collision stage's general CP pairs: the memory that follows the candidate pairs (remapCache),
// the paper model's carried contacts (reuse) and the narrow phase of every pair the crossings do not
// cover (geometry functors: geom/GapFunction for model Gap, the SAT for model Paper).
#include "engine/CollisionStage.hpp"
#include "core/Parallel.hpp"
#include "engine/StageUtil.hpp"
#include "geom/GapFunction.hpp"
#include "geom/SegmentDistance.hpp"
#include "geom/SeparatingAxis.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

using namespace stage;  // engine/StageUtil.hpp

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

}  // namespace woven
