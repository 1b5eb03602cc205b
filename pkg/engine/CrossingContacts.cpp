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
// A Newton step of the closest points that moves them less than this has converged [m] (1e-6 of a
// KM2 yarn's thickness); track makes at most kTrackSteps a step (one, once converged: the points
// move far less than a CP in a step), form kFormSteps from a chord pair's point.
constexpr Real kConverged = 1e-10;
constexpr int kTrackSteps = 3, kFormSteps = 30;
// Most a crossing's points may move in one step, in CP lengths (Slide beyond).
constexpr Real kJump = 0.25;
// How much less than the chords' gap a new crossing's gap may read, of its measure (the chords cut
// inside a smooth crossing: they read up to 2 % of the measure less there, never more).
constexpr Real kFormSlack = 0.05;
// Footprint reach beyond the other yarn's widest half-width: the CPs' stretch (rest lengths measure
// the arc) and the margin.
constexpr Real kFootprintStretch = 1.1;

inline Vec3 chord(const Fabric& f, Index e) {
  const Index i = f.elem0[e];
  return (f.pos[i + 1] - f.pos[i]).normalized();
}
}  // namespace

void CrossingContacts::reset(const Fabric& f) {
  all_.clear();
  foot_.reset(f.nElems());
  counts = CrossingCounts{};
}

// The cosine of the sharpest turn of the chain at CP e's two nodes (1: straight there).
Real CrossingContacts::straightness(const Fabric& f, Index e) {
  const Yarn& y = f.yarns[f.elemYarn[e]];
  const Vec3 t = chord(f, e);
  Real c = 1;
  if (e > y.firstElem) c = std::min(c, chord(f, e - 1).dot(t));
  if (e + 1 < y.firstElem + y.nElems) c = std::min(c, chord(f, e + 1).dot(t));
  return c;
}

// The CP e and its neighbours in its yarn are alive: the line on e reads their nodes.
bool CrossingContacts::stencilAlive(const Fabric& f, Index e) const {
  const Yarn& y = f.yarns[f.elemYarn[e]];
  for (Index k = std::max(e - 1, y.firstElem); k <= std::min(e + 1, y.firstElem + y.nElems - 1); ++k)
    if (!f.alive[k]) return false;
  return true;
}

// The CPs of each yarn whose rest-length arc comes within the other yarn's widest half-width (at
// the MCD) of the crossing's point.
void CrossingContacts::footprint(const Fabric& f, const Crossing& x, const ContactParams& p, Index& a0, Index& a1,
                                 Index& b0, Index& b1) const {
  const auto run = [&](const YarnPlace& q, const YarnPlace& other, Index& lo, Index& hi) {
    const Index node = f.elem0[other.cp] + (other.s < 0.5 ? 0 : 1);
    const Real reach = kFootprintStretch * semiAxes(f.secRadius[node], p.mcd, p.rule).a + p.margin;
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

bool CrossingContacts::track(const Fabric& f, const ContactParams& p, std::vector<std::uint8_t>& renew) {
  const Index n = static_cast<Index>(all_.size());
  gone_.assign(all_.size(), 0);
  returned_.clear();
  bool grew = false;
  for (Index id = 0; id < n; ++id) {
    Crossing& x = all_[id];
    if (!stencilAlive(f, x.a.cp) || !stencilAlive(f, x.b.cp)) {
      handBack(id, HandBack::Break, renew);
      continue;
    }
    YarnPlace a = x.a, b = x.b;
    Real moved = 0, travel = 0;
    for (int k = 0; k < kTrackSteps; ++k) {
      moved = closestStep(f, a, b);
      if (moved < 0) break;
      travel += moved;
      if (moved <= kConverged) break;
    }
    if (moved < 0) {
      handBack(id, moved == kLeftYarn ? HandBack::Slide : HandBack::Turn, renew);
      continue;
    }
    // The closest points jumped rather than slid (a quarter CP in a step is thousands of m/s: the
    // lines' closest approach moved to another place, a kinked or folded piece's).
    if (travel > kJump * std::min(f.restLength[x.a.cp], f.restLength[x.b.cp])) {
      handBack(id, HandBack::Slide, renew);
      continue;
    }
    canonical(f, a), canonical(f, b);
    if (!stencilAlive(f, a.cp) || !stencilAlive(f, b.cp)) {
      handBack(id, HandBack::Break, renew);
      continue;
    }
    if (std::abs(chord(f, a.cp).dot(chord(f, b.cp))) > kTurnCos) {
      handBack(id, HandBack::Turn, renew);
      continue;
    }
    if (std::min(straightness(f, a.cp), straightness(f, b.cp)) < kKinkCos) {
      handBack(id, HandBack::Kink, renew);
      continue;
    }
    const Real apart = (yarnCurveAt(f, b.cp, b.s).x - yarnCurveAt(f, a.cp, a.s).x).norm() -
                       semiAxesAt(f, a.cp, a.s, p.rule).b - semiAxesAt(f, b.cp, b.s, p.rule).b;
    const Index na = f.elem0[a.cp] + (a.s < 0.5 ? 0 : 1), nb = f.elem0[b.cp] + (b.s < 0.5 ? 0 : 1);
    if (apart > f.secRadius[na] + f.secRadius[nb]) {
      handBack(id, HandBack::Separation, renew);
      continue;
    }
    x.a = a, x.b = b;
    Index a0, a1, b0, b1;
    footprint(f, x, p, a0, a1, b0, b1);
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

bool CrossingContacts::form(const Fabric& f, const std::vector<CPContact>& contacts, const ContactParams& p) {
  bool any = false;
  for (const CPContact& c : contacts) {
    if (c.kind != ContactKind::Cross || f.elemYarn[c.cpA] == f.elemYarn[c.cpB]) continue;
    if (foot_.covers(c.cpA, c.cpB)) continue;  // a crossing formed from an earlier contact of the step
    if (std::abs(chord(f, c.cpA).dot(chord(f, c.cpB))) > kFormCos) continue;
    if (!stencilAlive(f, c.cpA) || !stencilAlive(f, c.cpB)) continue;
    Crossing x;
    x.a = {c.cpA, c.sA}, x.b = {c.cpB, c.sB};
    if (!closestPlaces(f, x.a, x.b, kConverged, kFormSteps)) continue;
    canonical(f, x.a), canonical(f, x.b);
    if (!stencilAlive(f, x.a.cp) || !stencilAlive(f, x.b.cp) || foot_.covers(x.a.cp, x.b.cp)) continue;
    if (std::abs(chord(f, x.a.cp).dot(chord(f, x.b.cp))) > kFormCos) continue;
    if (std::min(straightness(f, x.a.cp), straightness(f, x.b.cp)) < kFormKinkCos) continue;
    // The lines' points on the contact's side and no closer than its chords: else the general
    // pipeline keeps the pair.
    CPContact g;
    crossingGap(f, x.a.cp, x.a.s, x.b.cp, x.b.s, p.rule, c.normal, g);
    if (g.gap + g.hA + g.hB < 0 || g.gap < c.gap - kFormSlack * (g.hA + g.hB)) continue;
    footprint(f, x, p, x.fa0, x.fa1, x.fb0, x.fb1);
    if (!foot_.room(x.fa0, x.fa1, x.fb0, x.fb1)) continue;
    x.normal = g.normal;  // the pair's side, as its contact holds it
    // The measure memory holds the crossing's gap at the chords' where the lines read less (they
    // may cut inside a kinked chord): the crossing takes over without a new overlap.
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

void CrossingContacts::exclude(std::vector<CPPair>& pairs) const {
  pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                             [&](const CPPair& q) { return foot_.covers(q.a, q.b); }),
              pairs.end());
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
}

void CrossingContacts::keepImpulses(const std::vector<CPContact>& contacts, const std::vector<Real>& lambda) {
  for (Crossing& x : all_) x.lambda = 0;
  for (std::size_t k = 0; k < contacts.size() && k < lambda.size(); ++k)
    if (contacts[k].crossing >= 0) all_[contacts[k].crossing].lambda = lambda[k];
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
    if (!foot_.room(y.fa0, y.fa1, y.fb0, y.fb1))
      throw ParameterError("state", "crossings crowding a CP", "at most 8 crossings per CP");
    foot_.add(static_cast<Index>(all_.size()), y.fa0, y.fa1, y.fb0, y.fb1);
    all_.push_back(y);
  }
  counts.live = static_cast<long>(all_.size());
}

}  // namespace woven
