// The box separating-axis test (pkg/geom/SeparatingAxis) against an exact oracle: the same 15-axis
// test (Eberly; Gottschalk's OBBTree) evaluated in __float128 on the boxes exactly as given in double,
// on 1e5 static and 1e5 moving pairs at yarn scale (0.03-1 mm), chosen where double precision is
// hardest: near-parallel edges (1e-9 to 1e-2 rad, log-uniform), face/edge ties, picometre
// separations on both sides of touching, thin yarn-shaped boxes crossing and side by side. (1e4 of
// each in Debug/sanitizer builds, chain_util's runLength.)
//
// Why __float128 is exact enough: its significand has 113 bits and a product of two doubles needs at
// most 106, so every component of an edge axis A_i x B_j is the exact cross product of the double
// axes rounded once to 113 bits (relative error 1e-34 however small |A_i x B_j| is: no cancellation
// is left to amplify). The later steps (projections, radii, sums, divisions) add ~1e-34 of the box
// size, the square root that normalises the axes (a double seed and one Newton step) 1e-32. The
// oracle is thus ~1e16 times finer than the tolerances below (1e-15 m on boxes of 1e-3 m); it shares
// no code with pkg/geom (no closed-form radii from C = A^T B, no orthonormality assumed: radii are
// sums of e_k |n . A_k| over the actual axis vectors).
//
// Assertions, each counted over all pairs and reported with the worst case. On the code before the
// fix (ac50933) they failed on: verdict 110 (obbContact) and 110 (obbOverlap) pairs, depth 1472,
// normal 109, contact points 6538; moving: hit 33, first-contact time 274, contact points 6368.
//  - verdict: obbContact's and obbOverlap's yes/no equal the oracle's, except in the band
//    |separation| <= kBand = 2e-12 x size (size = sum of the six half extents; the code may count
//    boxes within kAxisEpsilon x size of touching as touching);
//  - depth (slop = 0): |depth - max(d*, 0)| <= max(1e-9 |d*|, 1e-15 m) for d* the exact minimum over
//    the 15 axes (edge axes normalised exactly), and never below -slop = 0;
//  - normal: when the minimum is unique (every axis more than 1e-9 rad away from the oracle's has a
//    depth larger by more than the depth tolerance) the normal is the oracle's within 1e-9 rad, and
//    in any case the exact overlap of the boxes along the reported (oriented) normal is d*;
//  - points: at least one; each on its own box within 1e-9 m and inside the other within
//    |depth| + 1e-9 m (outside() metric);
//  - moving verdict: hit equals the oracle's unless the answer changes when the boxes grow or
//    shrink by kBand or the step by 1e-9 dt;
//  - first-contact time: within [t(+kBand), t(-kBand)] +- 1e-9 dt, t(delta) being the oracle's
//    first time of contact of the boxes grown by delta (a grazing approach is only as well posed as
//    that interval; a head-on one gives t* +- 1e-9 dt).
#include "box_util.hpp"
#include "chain_util.hpp"
#include "geom/SeparatingAxis.hpp"
#include <gtest/gtest.h>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace woven;
using namespace woven_test;

namespace {

// ---------------------------------------------------------------- exact oracle (__float128)
using Q = __float128;
struct QV {
  Q x, y, z;
};
inline QV qv(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
inline Q dot(const QV& a, const QV& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline QV cross(const QV& a, const QV& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline QV scaled(const QV& a, Q s) { return {a.x * s, a.y * s, a.z * s}; }
inline Q qabs(Q x) { return x < 0 ? -x : x; }
inline Q qsqrt(Q x) {  // a double seed (relative error 1e-16) and one Newton step: 1e-32
  if (!(x > 0)) return 0;
  const Q y = std::sqrt(static_cast<double>(x));
  return (y + x / y) / 2;
}
constexpr Real kHuge = 1e300;

struct OracleAxis {
  QV n;             // unit axis (exactly normalised)
  Q s = 0, w = 0;   // n . D and n . W (centre distance and relative velocity along n)
  Q r = 0;          // r_A + r_B: the projection radii
  bool valid = false;
};

struct Oracle {
  std::array<QV, 3> A, B;
  Vec3 ea, eb;
  QV D, W;
  std::array<OracleAxis, 15> ax;
  Q depth = kHuge;  // exact minimum over the axes of r - |s| (< 0: separated by that much)
  int best = -1;

  // Exact radius of both boxes projected on the unit axis n.
  Q radii(const QV& n) const {
    Q r = 0;
    for (int k = 0; k < 3; ++k) r += Q(ea[k]) * qabs(dot(n, A[k])) + Q(eb[k]) * qabs(dot(n, B[k]));
    return r;
  }
  // Exact penetration along the double unit vector n oriented from A to B: the push of B along n
  // that brings the boxes into touch (negative: gap).
  Q overlapAlong(const Vec3& nd) const {
    QV n = qv(nd);
    n = scaled(n, 1 / qsqrt(dot(n, n)));
    return radii(n) - dot(n, D);
  }
  // The same boxes (axes and extents) at other centres, moving at the relative velocity W: only the
  // projections of D and W change.
  void place(const OBB& a, const OBB& b, const Vec3& Wd) {
    const QV ca = qv(a.centre), cb = qv(b.centre);
    D = {cb.x - ca.x, cb.y - ca.y, cb.z - ca.z};
    W = qv(Wd);
    depth = kHuge, best = -1;
    for (int k = 0; k < 15; ++k) {
      OracleAxis& x = ax[k];
      if (!x.valid) continue;
      x.s = dot(x.n, D);
      x.w = dot(x.n, W);
      const Q d = x.r - qabs(x.s);
      if (d < depth) depth = d, best = k;
    }
  }
  // Over t in [T0, T1] the boxes grown by delta [m] along every axis overlap for t in
  // [lo, hi] (the 15 per-axis intervals |s + w t| <= r + delta intersected): false if empty.
  bool moving(Q delta, Q T0, Q T1, Q* tFirst) const {
    Q lo = -kHuge, hi = kHuge;
    for (const OracleAxis& a : ax) {
      if (!a.valid) continue;
      const Q R = a.r + delta;
      if (a.w == 0) {
        if (qabs(a.s) > R) return false;
        continue;
      }
      Q t1 = (-R - a.s) / a.w, t2 = (R - a.s) / a.w;
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > lo) lo = t1;
      if (t2 < hi) hi = t2;
    }
    if (lo > hi || lo > T1 || hi < T0) return false;
    if (tFirst) *tFirst = lo;
    return true;
  }
};

Oracle oracle(const OBB& a, const OBB& b, const Vec3& W = Vec3::Zero()) {
  Oracle o;
  for (int k = 0; k < 3; ++k) o.A[k] = qv(a.axis(k)), o.B[k] = qv(b.axis(k));
  o.ea = a.extent, o.eb = b.extent;
  for (int k = 0; k < 15; ++k) {
    const QV L = k < 3 ? o.A[k] : k < 6 ? o.B[k - 3] : cross(o.A[(k - 6) / 3], o.B[(k - 6) % 3]);
    const Q len2 = dot(L, L);
    OracleAxis& x = o.ax[k];
    if (!(len2 > 0)) continue;  // exactly parallel edges: not an axis
    x.valid = true;
    x.n = scaled(L, 1 / qsqrt(len2));
    x.r = o.radii(x.n);
  }
  o.place(a, b, W);
  return o;
}

Vec3 toVec(const QV& v) { return Vec3(static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z)); }

// ---------------------------------------------------------------- pairs
enum Kind { Ordinary, NearParallel, Tie, YarnCross, YarnSide, nKinds };
const char* kKindName[nKinds] = {"ordinary", "near-parallel", "face/edge tie", "yarn crossing", "yarn side by side"};

struct Gen {
  std::mt19937 rng;
  explicit Gen(unsigned seed) : rng(seed) {}
  Real uni(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(rng); }
  Real logUni(Real lo, Real hi) { return std::exp(uni(std::log(lo), std::log(hi))); }
  Real sign() { return uni(0, 1) < 0.5 ? -1.0 : 1.0; }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
  Vec3 unit() {
    std::normal_distribution<Real> g(0, 1);
    return Vec3(g(rng), g(rng), g(rng)).normalized();
  }
  Mat3 rotation(const Vec3& axis, Real angle) { return Eigen::AngleAxis<Real>(angle, axis).toRotationMatrix(); }
  // Exact rotation by phi about local axis m (the m-th row and column are exactly e_m).
  Mat3 aboutLocal(int m, Real phi) {
    Mat3 R = Mat3::Identity();
    const int p = (m + 1) % 3, q = (m + 2) % 3;
    R(p, p) = std::cos(phi), R(p, q) = -std::sin(phi), R(q, p) = std::sin(phi), R(q, q) = std::cos(phi);
    return R;
  }
  // A proper signed permutation: b_j = +-a_{perm(j)} exactly.
  Mat3 signedPermutation() {
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng);
    Mat3 P = Mat3::Zero();
    for (int j = 0; j < 3; ++j) P(perm[j], j) = sign();
    if (P.determinant() < 0) P.col(2) *= -1;
    return P;
  }
  Vec3 ordinaryExtent() { return Vec3(uni(0.05e-3, 1e-3), uni(0.05e-3, 1e-3), uni(0.05e-3, 1e-3)); }
  Vec3 yarnExtent() { return Vec3(0.1e-3 * uni(0.8, 1.25), 0.3e-3 * uni(0.8, 1.25), 0.03e-3 * uni(0.8, 1.25)); }
  Vec3 anyExtent() { return uni(0, 1) < 0.5 ? ordinaryExtent() : yarnExtent(); }
  Real nearParallelAngle() { return logUni(1e-9, 1e-2); }
  // Picometre separations on either side of touching, or a depth from 1 nm to 50 um.
  Real target(Real pDeep) { return uni(0, 1) < pDeep ? logUni(1e-9, 5e-5) : sign() * logUni(1e-14, 1e-10); }
};

// B's radius along A's axis k.
Real radiusAlong(const OBB& b, const Vec3& n) { return (b.axes.transpose() * n).cwiseAbs().dot(b.extent); }

struct Pair {
  OBB a, b;
  Kind kind;
  Oracle o;  // of (a, b)
  bool exact = false;
};

// Moves b along the oracle's minimum axis so that the depth along it becomes `depth` (the minimum
// can then only be there or shallower).
void setDepth(Pair& p, Real depth) {
  p.o = oracle(p.a, p.b);
  const OracleAxis& x = p.o.ax[p.o.best];
  p.b.centre += static_cast<double>(p.o.depth - Q(depth)) * (x.s < 0 ? -1.0 : 1.0) * toVec(x.n);
  p.o.place(p.a, p.b, Vec3::Zero());
  p.exact = true;
}

Pair makePair(Gen& g, Kind kind) {
  Pair p;
  p.kind = kind;
  OBB &a = p.a, &b = p.b;
  a.centre = Vec3(g.uni(-5e-3, 5e-3), g.uni(-5e-3, 5e-3), g.uni(-5e-3, 5e-3));  // fabric coordinates
  switch (kind) {
    case Ordinary: {
      a.axes = randomRotation(g.rng), b.axes = randomRotation(g.rng);
      a.extent = g.anyExtent(), b.extent = g.anyExtent();
      const Vec3 reach = a.extent + b.extent;
      b.centre = a.centre + Vec3(g.uni(-1, 1) * reach.maxCoeff(), g.uni(-1, 1) * reach.maxCoeff(), g.uni(-1, 1) * reach.maxCoeff());
      if (g.uni(0, 1) < 0.3) setDepth(p, g.target(0.2));
      break;
    }
    case NearParallel: {
      a.axes = randomRotation(g.rng);
      a.extent = g.anyExtent(), b.extent = g.anyExtent();
      const Real theta = g.nearParallelAngle();
      const int i = g.pick(3);  // a_i is nearly parallel to an axis of B
      const Mat3 base = g.uni(0, 1) < 0.5 ? g.signedPermutation() : g.aboutLocal(i, g.uni(0.3, 2.8));
      b.axes = a.axes * base * g.rotation(g.unit(), theta);
      // Corner to corner across the two other axes (where the edge axes along a_i matter), anywhere
      // along a_i.
      Vec3 local;
      for (int k = 0; k < 3; ++k) {
        const Real reach = a.extent[k] + radiusAlong(b, a.axis(k));
        local[k] = g.sign() * reach * (k == i ? g.uni(0, 1) : g.uni(0, 1) < 0.5 ? 1.0 : g.uni(0.7, 1.02));
      }
      b.centre = a.centre + a.axes * local;
      if (g.uni(0, 1) < 0.7) setDepth(p, g.target(0.2));
      break;
    }
    case Tie: {
      a.axes = randomRotation(g.rng);
      a.extent = g.anyExtent(), b.extent = g.anyExtent();
      const int m = g.pick(3);  // stacked along a_m; the edge axes of the edges across a_m are a_m itself
      const Real phi = g.uni(0, 1) < 0.2 ? g.pick(8) * M_PI / 4 : g.uni(0, 2 * M_PI);
      b.axes = a.axes * g.aboutLocal(m, phi);
      if (g.uni(0, 1) < 0.5) b.axes = b.axes * g.rotation(g.unit(), g.logUni(1e-15, 1e-6));
      Vec3 local;
      for (int k = 0; k < 3; ++k) {
        const Real reach = a.extent[k] + radiusAlong(b, a.axis(k));
        local[k] = k == m ? g.sign() * reach : g.uni(-0.9, 0.9) * reach;
      }
      b.centre = a.centre + a.axes * local;
      setDepth(p, g.target(0.5));
      break;
    }
    case YarnCross: {
      // Warp along x, weft along y (crimped about their width axes), thickness along z; the
      // section axes A2, B2 meet at the crimp angles, anything from exactly 0 up.
      a.extent = g.yarnExtent(), b.extent = g.yarnExtent();
      auto angle = [&]() {
        const int c = g.pick(3);
        return c == 0 ? 0.0 : c == 1 ? g.uni(-0.3, 0.3) : g.sign() * g.nearParallelAngle();
      };
      const Mat3 R0 = randomRotation(g.rng);
      a.axes = R0 * g.aboutLocal(1, angle());
      b.axes = R0 * g.aboutLocal(2, M_PI / 2 + angle()) * g.aboutLocal(1, angle());
      const Vec3 local(g.uni(-0.2e-3, 0.2e-3), g.uni(-0.2e-3, 0.2e-3), a.extent[2] + b.extent[2]);
      b.centre = a.centre + R0 * local;
      setDepth(p, g.uni(0, 1) < 0.5 ? g.uni(0, 45e-6) : g.target(0));
      break;
    }
    default: {  // YarnSide: neighbouring parallel yarns touching along their width
      a.extent = g.yarnExtent(), b.extent = g.yarnExtent();
      a.axes = randomRotation(g.rng);
      b.axes = a.axes * g.rotation(g.unit(), g.nearParallelAngle());
      const Vec3 local(g.uni(-1, 1) * (a.extent[0] + b.extent[0]), g.sign() * (a.extent[1] + b.extent[1]),
                       g.uni(-0.5, 0.5) * (a.extent[2] + b.extent[2]));
      b.centre = a.centre + a.axes * local;
      if (g.uni(0, 1) < 0.7) setDepth(p, g.target(0.2));
      break;
    }
  }
  if (!p.exact) p.o = oracle(a, b);
  return p;
}

// ---------------------------------------------------------------- tallies
struct Tally {
  explicit Tally(const char* w) : what(w) {}
  const char* what;
  long fails[nKinds] = {};
  long checked = 0;
  double worst = 0;    // largest violation, in units of the tolerance
  double largest = 0;  // largest excess among the passes (their margin; 0 for yes/no checks)
  std::string example, largestExample;
  void check(bool ok, Kind kind, double excess, const std::string& detail) {
    ++checked;
    if (ok) {
      if (excess > largest) largest = excess, largestExample = detail;
      return;
    }
    ++fails[kind];
    if (excess > worst || example.empty()) worst = excess, example = detail;
  }
  long total() const {
    long n = 0;
    for (long f : fails) n += f;
    return n;
  }
  void print() const {
    std::printf("  %-24s %7ld failed of %8ld checked, largest %.3g of the tolerance", what, total(), checked, largest);
    if (total()) {
      std::printf("  (");
      for (int k = 0; k < nKinds; ++k)
        if (fails[k]) std::printf(" %s %ld", kKindName[k], fails[k]);
      std::printf(" )\n      worst: %s", example.c_str());
    }
    std::printf("\n");
    if (std::getenv("SAT_ORACLE_VERBOSE") && largest > 0) std::printf("      largest: %s\n", largestExample.c_str());
  }
};

template <class... T>
std::string fmt(const char* f, T... x) {  // every argument printed as a double (%g, %.0f)
  char buf[400];
  std::snprintf(buf, sizeof buf, f, static_cast<double>(x)...);
  return buf;
}

constexpr Real kBand = 2e-12;     // verdict band, relative to the size (sum of the six half extents)
constexpr Real kDepthAbs = 1e-15; // [m]
constexpr Real kDepthRel = 1e-9;
constexpr Real kPointTol = 1e-9;  // [m]
constexpr Real kAngleTol = 1e-9;  // [rad]
constexpr Real kTimeTol = 1e-9;   // of dt

Real sizeOf(const OBB& a, const OBB& b) { return a.extent.sum() + b.extent.sum(); }

void checkPoints(Tally& t, const OBB& a, const OBB& b, const BoxContact& c, Kind kind, long id) {
  double excess = c.nPoints > 0 ? 0 : 2;  // none: fails
  for (int i = 0; i < c.nPoints; ++i) {
    const BoxContactPoint& p = c.points[i];
    const Real allowed = std::abs(c.depth) + kPointTol;
    excess = std::max({excess, std::abs(a.outside(p.onA)) / kPointTol, std::abs(b.outside(p.onB)) / kPointTol,
                       b.outside(p.onA) / allowed, a.outside(p.onB) / allowed});
  }
  t.check(excess <= 1, kind,
          excess, fmt("pair %.0f axis %.0f, %.0f points: worst %.3g of the allowance (depth %.3g m)", id, c.axis,
                      c.nPoints, excess, c.depth));
}

}  // namespace

TEST(SatOracle, StaticPairsMatchTheExactOracle) {
  const long pairs = runLength(100000, 10);
  Gen g(20261130);
  Tally verdict{"verdict (obbContact)"}, overlapVerdict{"verdict (obbOverlap)"}, depth{"depth"}, normal{"normal"},
      points{"contact points"};
  long overlapping = 0, edgeBest = 0, inBand = 0;
  for (long id = 0; id < pairs; ++id) {
    const Pair p = makePair(g, Kind(id % nKinds));
    const OBB &a = p.a, &b = p.b;
    const Oracle& o = p.o;
    const Real d = static_cast<double>(o.depth), size = sizeOf(a, b);
    const BoxContact c = obbContact(a, b);
    const bool yes = obbOverlap(a, b);
    const bool band = std::abs(d) <= kBand * size;
    inBand += band;
    if (!band) {
      const double excess = -d / size / kBand;  // separation in units of the band
      verdict.check(c.overlap == (d > 0), p.kind, c.overlap == (d > 0) ? 0 : std::abs(excess),
                    fmt("pair %.0f: exact depth %.4g m (%.3g x size), obbContact says %.0f, axis %.0f", id, d, d / size,
                        c.overlap, c.axis));
      overlapVerdict.check(yes == (d > 0), p.kind, yes == (d > 0) ? 0 : std::abs(excess),
                           fmt("pair %.0f: exact depth %.4g m (%.3g x size), obbOverlap says %.0f", id, d, d / size, yes));
    }
    if (!c.overlap) continue;
    ++overlapping;
    edgeBest += o.best >= 6;
    // depth: the exact minimum (clamped at -slop = 0), never below -slop
    const Real tol = std::max(kDepthRel * std::abs(d), kDepthAbs);
    const Real expected = std::max(d, 0.0);
    const double dErr = std::abs(c.depth - expected) / tol;
    depth.check(dErr <= 1 && c.depth >= 0, p.kind, c.depth < 0 ? 1e300 : dErr,
                fmt("pair %.0f: depth %.6g m, exact %.6g m (error %.3g of the tolerance), axis %.0f, exact axis %.0f", id,
                    c.depth, d, dErr, c.axis, o.best));
    // normal: the oracle's when unique; always an axis along which the exact overlap is the depth
    const Vec3 nStar = toVec(o.ax[o.best].n) * (o.ax[o.best].s < 0 ? -1.0 : 1.0);
    Q second = kHuge;
    for (const OracleAxis& x : o.ax)
      if (x.valid && std::abs(static_cast<double>(dot(x.n, o.ax[o.best].n))) < std::cos(kAngleTol))
        second = std::min(second, x.r - qabs(x.s));
    const bool unique = static_cast<double>(second - o.depth) > tol;
    const Real sAbs = std::abs(static_cast<double>(o.ax[o.best].s));
    // |n - n*| is the angle for small ones (acos cannot resolve below ~1e-8); unoriented when the
    // centres project on the same point (both orientations are then minimal)
    const double angle = sAbs > tol ? (c.normal - nStar).norm()
                                    : std::min((c.normal - nStar).norm(), (c.normal + nStar).norm());
    const double along = std::abs(static_cast<double>(o.overlapAlong(c.normal)) - d) / tol;
    const double nErr = std::max(unique ? angle / kAngleTol : 0.0, along);
    normal.check(nErr <= 1, p.kind, nErr,
                 fmt("pair %.0f: angle to the exact normal %.3g rad (unique %.0f), exact overlap along it %.6g m for "
                     "depth %.6g m",
                     id, angle, unique, static_cast<double>(o.overlapAlong(c.normal)), d));
    checkPoints(points, a, b, c, p.kind, id);
  }
  std::printf("static pairs %ld: %ld overlapping, exact minimum on an edge axis in %ld, %ld in the verdict band\n", pairs,
              overlapping, edgeBest, inBand);
  for (const Tally* t : {&verdict, &overlapVerdict, &depth, &normal, &points}) t->print();
  EXPECT_EQ(verdict.total(), 0);
  EXPECT_EQ(overlapVerdict.total(), 0);
  EXPECT_EQ(depth.total(), 0);
  EXPECT_EQ(normal.total(), 0);
  EXPECT_EQ(points.total(), 0);
  EXPECT_GT(edgeBest, pairs / 20);  // the hard cases are there
  EXPECT_GT(overlapping, pairs / 4);
}

TEST(SatOracle, MovingPairsMatchTheExactOracle) {
  const long pairs = runLength(100000, 10);
  const Real dt = 1e-7;  // [s], a fabric step
  Gen g(777);
  Tally hitVerdict{"hit verdict"}, time{"first-contact time"}, points{"contact points (moving)"};
  long hits = 0, ambiguous = 0, wellPosed = 0;
  double wellPosedError = 0;  // largest |t - t*| / dt where [t(+kBand), t(-kBand)] is narrower than 1e-9 dt
  for (long id = 0; id < pairs; ++id) {
    const Pair p = makePair(g, Kind(id % nKinds));  // the configuration at the time tc
    const Real size = sizeOf(p.a, p.b), speed = g.uni(0.05, 2) * size / 3 / dt;
    const Oracle& o = p.o;
    Vec3 n = toVec(o.ax[o.best].n) * (o.ax[o.best].s < 0 ? -1.0 : 1.0);
    Vec3 dir;  // of W = vb - va
    const int mode = g.pick(3);
    if (mode == 0) dir = g.unit();
    else if (mode == 1) dir = (-n + 0.1 * g.unit()).normalized();  // head on
    else {                                                          // grazing
      Vec3 t = g.unit();
      t = (t - t.dot(n) * n).normalized();
      const Real lean = g.logUni(1e-9, 1e-1);
      dir = (t - lean * n).normalized();
    }
    const Vec3 va = g.uni(0, 1) * speed * g.unit(), vb = va + speed * dir;
    const Real tc = g.uni(-0.2, 1.2) * dt;
    OBB a0 = p.a, b0 = p.b;
    a0.centre -= va * tc, b0.centre -= vb * tc;
    Oracle m = o;  // the same boxes, moved back to t = 0
    m.place(a0, b0, vb - va);
    const SweptContact s = obbFirstContact(a0, va, b0, vb, dt);
    const Q delta = kBand * size, eta = kTimeTol * dt;
    Q tEarly = 0, tLate = 0;
    const bool loose = m.moving(delta, -eta, dt + eta, &tEarly), strict = m.moving(-delta, eta, dt - eta, &tLate);
    if (loose != strict) ++ambiguous;
    else
      hitVerdict.check(s.hit == strict, p.kind, s.hit == strict ? 0 : 1,
                       fmt("pair %.0f: exact hit %.0f (t %.6g of dt), obbFirstContact says %.0f at %.6g of dt", id, strict,
                           static_cast<double>(strict ? tLate : tEarly) / dt, s.hit, s.time / dt));
    if (!s.hit) continue;
    ++hits;
    if (strict) {
      const Real lo = std::max(0.0, static_cast<double>(tEarly)), hi = std::max(0.0, static_cast<double>(tLate));
      const double excess = std::max(lo - s.time, s.time - hi) / (kTimeTol * dt);
      if (hi - lo < kTimeTol * dt) {
        Q t0 = 0;
        if (m.moving(0, 0, dt, &t0)) {
          ++wellPosed;
          wellPosedError = std::max(wellPosedError, std::abs(s.time - std::max(0.0, static_cast<double>(t0))) / dt);
        }
      }
      time.check(excess <= 1, p.kind, excess,
                 fmt("pair %.0f: time %.9g of dt, exact window [%.9g, %.9g] of dt (off by %.3g dt)", id, s.time / dt,
                     lo / dt, hi / dt, std::max(lo - s.time, s.time - hi) / dt));
    }
    OBB a1 = a0, b1 = b0;
    a1.centre += va * s.time, b1.centre += vb * s.time;
    if (s.contact.overlap) checkPoints(points, a1, b1, s.contact, p.kind, id);
  }
  std::printf("moving pairs %ld: %ld hits, %ld with an ambiguous verdict (band); |t - t*| <= %.3g dt on the %ld "
              "well-posed hits\n",
              pairs, hits, ambiguous, wellPosedError, wellPosed);
  for (const Tally* t : {&hitVerdict, &time, &points}) t->print();
  EXPECT_EQ(hitVerdict.total(), 0);
  EXPECT_EQ(time.total(), 0);
  EXPECT_EQ(points.total(), 0);
  EXPECT_GT(hits, pairs / 4);
}
