#include "engine/CrossingContacts.hpp"
#include "core/Errors.hpp"
#include "geom/GapFunction.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {
constexpr Real kPi = 3.14159265358979323846;
const Real kTurnCos = std::cos(CrossingContacts::kTurnDeg * kPi / 180);
const Real kFormCos = std::cos(CrossingContacts::kFormDeg * kPi / 180);
const Real kKinkCos = std::cos(CrossingContacts::kKinkDeg * kPi / 180);
const Real kFormKinkCos = std::cos(CrossingContacts::kFormKinkDeg * kPi / 180);
const Real kFoldCos = std::cos(CrossingContacts::kFoldDeg * kPi / 180);
// A Newton step of the closest points that moves them less than this has converged [m] (1e-6 of a
// KM2 yarn's thickness): form makes at most kFormSteps from a chord pair's point.
constexpr Real kConverged = 1e-10;
constexpr int kFormSteps = 30;
// A crossing's footprint is drawn for its places slid by up to this fraction of their CPs, and
// drawn again only when they have slid farther (or into another CP).
constexpr Real kFootprintSlide = 0.05;
// Most a crossing's points may move in one step, in CP lengths (Slide beyond).
constexpr Real kJump = 0.25;
// A tracking step that moved the places farther than this [m] is followed by another (track).
constexpr Real kRefine = 0.1e-6;

// Footprint reach beyond the other yarn's widest half-width: the CPs' stretch (rest lengths measure
// the arc) and the margin.
constexpr Real kFootprintStretch = 1.1;

}  // namespace

void CrossingContacts::reset(const Fabric& f) {
  all_.clear();
  foot_.reset(f.nElems());
  counts = CrossingCounts{};
}

// Whether a crossing's line may use CP e: 0 when e and its neighbours in its yarn are alive (the line
// on e reads their nodes) and the chain turns at e's two nodes by less than the angle of cosine
// kinkCos (`chord`: the CPs' unit chords); else the hand-back rule that fails, Break or Kink.
int CrossingContacts::usable(const Fabric& f, const Vec3Array& chord, Index e, Real kinkCos) {
  const Yarn& y = f.yarns[f.elemYarn[e]];
  const Index lo = std::max(e - 1, y.firstElem), hi = std::min(e + 1, y.firstElem + y.nElems - 1);
  int why = 0;
  for (Index k = lo; k <= hi; ++k) {
    if (!f.alive[k]) return 1 + static_cast<int>(HandBack::Break);
    if (chord[k].dot(chord[e]) < kinkCos) why = 1 + static_cast<int>(HandBack::Kink);
  }
  return why;
}

// Whether tracking would keep a crossing whose place q slid into the CP beside it, on the side of
// the node q lies nearer to (none at a yarn's end).
bool CrossingContacts::usableBeside(const Fabric& f, const Vec3Array& chord, const YarnPlace& q) {
  const Yarn& y = f.yarns[f.elemYarn[q.cp]];
  const Index e = q.s < 0.5 ? q.cp - 1 : q.cp + 1;
  if (e < y.firstElem || e >= y.firstElem + y.nElems) return true;
  return usable(f, chord, e, kKinkCos) == 0;
}

// Whether the footprint's CPs [lo, hi] of a yarn still are the piece its crossing stands for: 0 when
// all are alive and none turns from the point's CP e by more than the angle of cosine kFoldCos; else
// Break or Kink. The footprint hides its pairs from the general pipeline, so another close approach
// of the two yarns inside it (a broken end flying back, a piece folded over at 1000 m/s: a pair of it
// met 107 um deep when its crossing went) would be seen by nobody.
int CrossingContacts::whole(const Fabric& f, const Vec3Array& chord, Index lo, Index hi, Index e) {
  int why = 0;
  for (Index k = lo; k <= hi; ++k) {
    if (!f.alive[k]) return 1 + static_cast<int>(HandBack::Break);
    if (chord[k].dot(chord[e]) < kFoldCos) why = 1 + static_cast<int>(HandBack::Kink);
  }
  return why;
}

// The CPs of each yarn whose rest-length arc comes within the other yarn's widest half-width (at
// the MCD) of the crossing's point.
void CrossingContacts::footprint(const Fabric& f, const Crossing& x, const ContactParams& p, Index& a0, Index& a1,
                                 Index& b0, Index& b1) const {
  const auto run = [&](const YarnPlace& q, const YarnPlace& other, Index& lo, Index& hi) {
    const Index node = f.elem0[other.cp] + (other.s < 0.5 ? 0 : 1);
    const Real reach = kFootprintStretch * semiAxes(f.secRadius[node], p.mcd, p.rule).a + p.margin +
                       kFootprintSlide * f.restLength[q.cp];
    const Yarn& y = f.yarns[f.elemYarn[q.cp]];
    lo = hi = q.cp;
    for (Real d = q.s * f.restLength[q.cp]; lo > y.firstElem && d < reach; d += f.restLength[lo]) --lo;
    for (Real d = (1 - q.s) * f.restLength[q.cp]; hi + 1 < y.firstElem + y.nElems && d < reach; d += f.restLength[hi]) ++hi;
  };
  run(x.a, x.b, a0, a1);
  run(x.b, x.a, b0, b1);
}

void CrossingContacts::handBack(Index id, HandBack why, std::vector<std::uint8_t>& renew) {
  const Crossing& x = all_[id];
  returned_.push_back({x.fa0, x.fa1, x.fb0, x.fb1, x.normal});
  foot_.remove(id, x.fa0, x.fa1, x.fb0, x.fb1);
  for (Index e = x.fa0; e <= x.fa1; ++e) renew[e] = 1;
  for (Index e = x.fb0; e <= x.fb1; ++e) renew[e] = 1;
  gone_[id] = 1;
  ++counts.handedBack[static_cast<int>(why)];
}

// Each crossing's step (threads: it reads only the fabric and its own crossing), then what the
// steps decide applied in crossing order (the footprints are shared): the same bits for any thread
// count.
CrossingContacts::Step CrossingContacts::stepOne(const Fabric& f, const ContactParams& p, const Vec3Array& chord,
                                                 const Crossing& x) const {
  Step st;
  const auto give = [&](HandBack why) {
    st.verdict = 1 + static_cast<int>(why);
    return st;
  };
  const auto rule = [](int why) { return why == 1 + static_cast<int>(HandBack::Break) ? HandBack::Break : HandBack::Kink; };
  // A Newton step from the last step's closest points: they move far less than a CP a step, so
  // one step keeps them within (their motion)^2 / (the lines' curvature radius) of the exact ones;
  // up to two more where it moved more than kRefine (a fast slide over a rounded corner, whose
  // lag left a few um of overlap to the next step, more at a shorter time step).
  YarnPlace& a = st.a;
  YarnPlace& b = st.b;
  a = x.a, b = x.b;
  Real moved = closestStep(f, a, b, &st.apart), last = moved;
  for (int it = 0; it < 2 && last > kRefine; ++it) {
    last = closestStep(f, a, b, &st.apart);
    moved = last < 0 ? last : moved + last;
  }
  if (moved < 0) return give(moved == kLeftYarn ? HandBack::Slide : HandBack::Turn);
  // The closest points jumped rather than slid (a quarter CP in a step is thousands of m/s: the
  // lines' closest approach moved to another place, a kinked or folded piece's).
  if (moved > kJump * std::min(f.restLength[x.a.cp], f.restLength[x.b.cp])) return give(HandBack::Slide);
  canonical(f, a), canonical(f, b);
  if (const int why = std::max(usable(f, chord, a.cp, kKinkCos), usable(f, chord, b.cp, kKinkCos)); why > 0)
    return give(rule(why));
  if (const int why = std::max(whole(f, chord, x.fa0, x.fa1, a.cp), whole(f, chord, x.fb0, x.fb1, b.cp)); why > 0)
    return give(rule(why));
  if (std::abs(chord[a.cp].dot(chord[b.cp])) > kTurnCos) return give(HandBack::Turn);
  const Index na = f.elem0[a.cp] + (a.s < 0.5 ? 0 : 1), nb = f.elem0[b.cp] + (b.s < 0.5 ? 0 : 1);
  if (st.apart - semiAxesAt(f, a.cp, a.s, p.rule).b - semiAxesAt(f, b.cp, b.s, p.rule).b >
      f.secRadius[na] + f.secRadius[nb])
    return give(HandBack::Separation);
  // Its footprint (drawn kFootprintSlide wider) still holds, or the one at the new places.
  st.same = a.cp == x.a.cp && b.cp == x.b.cp && std::abs(a.s - x.fsA) <= kFootprintSlide &&
            std::abs(b.s - x.fsB) <= kFootprintSlide;
  if (!st.same) {
    Crossing y = x;
    y.a = a, y.b = b;
    footprint(f, y, p, st.fa0, st.fa1, st.fb0, st.fb1);
  }
  return st;
}

bool CrossingContacts::track(const Fabric& f, const ContactParams& p, const Vec3Array& chord,
                             std::vector<std::uint8_t>& renew) {
  const Index n = static_cast<Index>(all_.size());
  gone_.assign(all_.size(), 0);
  returned_.clear();
  steps_.resize(all_.size());
  parallelFor(n, 64, threads(), [&](Index id) { steps_[id] = stepOne(f, p, chord, all_[id]); });
  bool grew = false;
  for (Index id = 0; id < n; ++id) {
    Crossing& x = all_[id];
    const Step& st = steps_[id];
    if (st.verdict > 0) {
      handBack(id, static_cast<HandBack>(st.verdict - 1), renew);
      continue;
    }
    const YarnPlace &a = st.a, &b = st.b;
    x.a = a, x.b = b, x.apart = st.apart;
    if (st.same) continue;
    const Index a0 = st.fa0, a1 = st.fa1, b0 = st.fb0, b1 = st.fb1;
    x.fsA = a.s, x.fsB = b.s;
    if (a0 == x.fa0 && a1 == x.fa1 && b0 == x.fb0 && b1 == x.fb1) continue;
    // The footprint moved: the CPs it left return to the general pipeline, those it took leave it.
    foot_.remove(id, x.fa0, x.fa1, x.fb0, x.fb1);
    returned_.push_back({x.fa0, x.fa1, x.fb0, x.fb1, x.normal});
    for (Index e = x.fa0; e <= x.fa1; ++e) renew[e] |= e < a0 || e > a1;
    for (Index e = x.fb0; e <= x.fb1; ++e) renew[e] |= e < b0 || e > b1;
    // Onto another crossing of the same two yarns (a folded piece's two crossings slid together:
    // both would track the same point, one from the wrong side), or no room: handed back.
    if (foot_.covers(a.cp, b.cp) || !foot_.room(a0, a1, b0, b1)) {
      for (Index e = x.fa0; e <= x.fa1; ++e) renew[e] = 1;
      for (Index e = x.fb0; e <= x.fb1; ++e) renew[e] = 1;
      gone_[id] = 1;
      ++counts.handedBack[static_cast<int>(HandBack::Slide)];
      continue;
    }
    foot_.add(id, a0, a1, b0, b1);
    grew |= a0 < x.fa0 || a1 > x.fa1 || b0 < x.fb0 || b1 > x.fb1;
    x.fa0 = a0, x.fa1 = a1, x.fb0 = b0, x.fb1 = b1;
    ++counts.moved;
  }
  // The list compacted in order (the footprints' slots follow the new indices).
  Index k = 0;
  for (Index id = 0; id < n; ++id) {
    if (gone_[id]) continue;
    if (k != id) {
      const Crossing& x = all_[id];
      foot_.rename(id, k, x.fa0, x.fa1, x.fb0, x.fb1);
      all_[k] = x;
    }
    ++k;
  }
  all_.resize(static_cast<std::size_t>(k));
  counts.live = k;
  return grew;
}

bool CrossingContacts::form(const Fabric& f, const std::vector<CPContact>& contacts, const ContactParams& p,
                            const Vec3Array& chord) {
  bool any = false;
  for (const CPContact& c : contacts) {
    if (c.kind != ContactKind::Cross || f.elemYarn[c.cpA] == f.elemYarn[c.cpB]) continue;
    if (foot_.covers(c.cpA, c.cpB)) continue;  // a crossing formed from an earlier contact of the step
    if (std::abs(chord[c.cpA].dot(chord[c.cpB])) > kFormCos) continue;
    if (usable(f, chord, c.cpA, kFormKinkCos) || usable(f, chord, c.cpB, kFormKinkCos)) continue;
    Crossing x;
    x.a = {c.cpA, c.sA}, x.b = {c.cpB, c.sB};
    if (!closestPlaces(f, x.a, x.b, kConverged, kFormSteps)) continue;
    canonical(f, x.a), canonical(f, x.b);
    if (foot_.covers(x.a.cp, x.b.cp) || std::abs(chord[x.a.cp].dot(chord[x.b.cp])) > kFormCos) continue;
    if (usable(f, chord, x.a.cp, kFormKinkCos) || usable(f, chord, x.b.cp, kFormKinkCos)) continue;
    // Nor next to a CP tracking would hand it back on: a place near a node slides into the CP
    // beyond it within a step or two, and a crossing formed beside a kinked CP was formed and handed
    // back at every step (traced at 4 CPs per span, 24 steps running, its chord pairs leaving and
    // returning each time; docs/collisions.md).
    if (!usableBeside(f, chord, x.a) || !usableBeside(f, chord, x.b)) continue;
    // The lines' points on the contact's side: else the general pipeline keeps the pair.
    CPContact g;
    crossingGap(f, x.a.cp, x.a.s, x.b.cp, x.b.s, p.rule, c.normal, g);
    if (g.gap + g.hA + g.hB < 0) continue;
    footprint(f, x, p, x.fa0, x.fa1, x.fb0, x.fb1);
    if (!foot_.room(x.fa0, x.fa1, x.fb0, x.fb1)) continue;
    x.fsA = x.a.s, x.fsB = x.b.s;
    x.normal = g.normal;  // the pair's side, as its contact holds it
    // The measure memory holds the crossing's gap at the chords' where the lines read less (their
    // rounded corners cut inside the chords by up to lambda sin(phi / 2) / 2 a yarn): the crossing
    // takes over without a new overlap.
    const Real r = g.gap + g.hA + g.hB, least = std::min(c.gap, Real(0));
    if (g.gap < least) x.measure = r - least;
    foot_.add(static_cast<Index>(all_.size()), x.fa0, x.fa1, x.fb0, x.fb1);
    all_.push_back(x);
    ++counts.formed;
    any = true;
  }
  counts.live = static_cast<long>(all_.size());
  return any;
}

void CrossingContacts::exclude(std::vector<CPPair>& pairs) {
  keepChunked(pairs, pairs, 8192, keptPairs_, threads(), [&](const CPPair& q) { return !foot_.covers(q.a, q.b); });
}

void CrossingContacts::exclude(std::vector<CPContact>& contacts) const {
  contacts.erase(std::remove_if(contacts.begin(), contacts.end(),
                                [&](const CPContact& c) {
                                  return c.kind != ContactKind::Crossing && c.kind != ContactKind::Paper &&
                                         foot_.covers(c.cpA, c.cpB);
                                }),
                 contacts.end());
}

void CrossingContacts::measureOne(const Fabric& f, Index id, const ContactParams& p, CPContact& c) {
  Crossing& x = all_[id];
  crossingGap(f, x.a.cp, x.a.s, x.b.cp, x.b.s, p.rule, x.normal, c);
  // The measure memory (capMeasure): the sections' measure may grow only into room (a point moving
  // onto a rounder section).
  if (x.measure >= 0) capMeasure(c, x.measure);
  x.normal = c.normal, x.measure = c.hA + c.hB;
  c.crossing = id, c.warm = x.lambda;
  // What the lines' distance lost as the places moved to this step's closest points: the next
  // step's tracking will likely lose as much, which the rows hold back (CPContact::drift).
  const Real r = c.gap + c.hA + c.hB;
  c.drift = x.apart > r ? x.apart - r : 0.0;
}

// Threads: a crossing is listed at most once (measure).
void CrossingContacts::keepImpulses(const std::vector<CPContact>& contacts, const std::vector<Real>& lambda) {
  parallelFor(static_cast<Index>(all_.size()), kParallelGrain, threads(), [&](Index id) { all_[id].lambda = 0; });
  parallelFor(static_cast<Index>(std::min(contacts.size(), lambda.size())), kParallelGrain, threads(), [&](Index k) {
    if (contacts[k].crossing >= 0) all_[contacts[k].crossing].lambda = lambda[k];
  });
}

void CrossingContacts::set(const Fabric& f, const std::vector<Crossing>& all, const ContactParams& p) {
  const Index n = f.nElems();
  for (const Crossing& x : all) {
    const bool ok = x.a.cp >= 0 && x.a.cp < n && x.b.cp >= 0 && x.b.cp < n && x.a.s >= 0 && x.a.s <= 1 &&
                    x.b.s >= 0 && x.b.s <= 1 && f.elemYarn[x.a.cp] < f.elemYarn[x.b.cp] && x.normal.allFinite() &&
                    std::isfinite(x.measure) && std::isfinite(x.lambda) && x.lambda >= 0;
    if (!ok) throw ParameterError("state", "a crossing out of range", "crossings of this fabric's CPs (a state of this weave)");
  }
  reset(f);
  for (const Crossing& x : all) {
    Crossing y = x;
    footprint(f, y, p, y.fa0, y.fa1, y.fb0, y.fb1);
    y.fsA = y.a.s, y.fsB = y.b.s;
    if (!foot_.room(y.fa0, y.fa1, y.fb0, y.fb1))
      throw ParameterError("state", "crossings crowding a CP", "at most 8 crossings per CP");
    foot_.add(static_cast<Index>(all_.size()), y.fa0, y.fa1, y.fb0, y.fb1);
    all_.push_back(y);
  }
  counts.live = static_cast<long>(all_.size());
}

}  // namespace woven
