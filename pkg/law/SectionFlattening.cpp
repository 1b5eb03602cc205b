#include "law/SectionFlattening.hpp"
#include "geom/CPContact.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

Real flatteningDirection(const Fabric& f, const Vec3Array& tangent, Index k, const Vec3& n, Vec3& dir) {
  const Vec3 across = n - n.dot(tangent[k]) * tangent[k];
  const Real len = across.norm();
  if (len < kLateralCos) return 0;
  if (f.secFlat[k] == 0) {  // circular: free to turn
    dir = across / len;
    return len;
  }
  dir = f.secDir[k];
  const Real c = std::abs(n.dot(dir));
  return c >= kLateralCos ? c : 0;
}

namespace {

// Reach of node k's section along n from the CP's centre: |(x_k - c).n| + the ellipse's support.
struct NodeReach {
  Real now, min, cos;  // with eps as given, at the MCD, and the flattening cosine (0: cannot)
};
NodeReach reach(const Fabric& f, const Vec3Array& tangent, Index k, const Vec3& centre, const Vec3& n, Real eps,
                const ContactParams& p) {
  const Real offset = std::abs((f.pos[k] - centre).dot(n));
  const Vec3 u = tangent[k].cross(f.secDir[k]);
  const SemiAxes s = semiAxes(f.secRadius[k], eps, p.rule);
  const Real now = offset + ellipseSupport(u, f.secDir[k], s.a, s.b, n);
  Vec3 dir;
  const Real c = flatteningDirection(f, tangent, k, n, dir);
  if (c == 0) return {now, now, 0};
  const SemiAxes m = semiAxes(f.secRadius[k], p.mcd, p.rule);
  const Real atMcd = offset + ellipseSupport(tangent[k].cross(dir), dir, m.a, m.b, n);
  return {now, std::min(now, atMcd), c};
}

inline Vec3 cpCentre(const Fabric& f, Index e) { return 0.5 * (f.pos[f.elem0[e]] + f.pos[f.elem0[e] + 1]); }

}  // namespace

// The CP's extent along n is the larger reach of its two end sections: it shrinks until the larger
// of the two reaches at the MCD.
Real flatteningCapacity(const Fabric& f, const Vec3Array& tangent, Index e, const Vec3& n, const ContactParams& p,
                        const std::vector<Real>* flat) {
  const std::vector<Real>& eps = flat ? *flat : f.secFlat;
  const Vec3 c = cpCentre(f, e);
  const Index i = f.elem0[e];
  const NodeReach r0 = reach(f, tangent, i, c, n, eps[i], p);
  const NodeReach r1 = reach(f, tangent, i + 1, c, n, eps[i + 1], p);
  return std::max(Real(0), std::max(r0.now, r1.now) - std::max(r0.min, r1.min));
}

void flattenCP(Fabric& f, const Vec3Array& tangent, Index e, const Vec3& n, Real delta, const ContactParams& p,
               const std::vector<Real>& flatBefore, Vec3Array& dirSum) {
  if (!(delta > 0)) return;
  const Vec3 c = cpCentre(f, e);
  const Index i = f.elem0[e];
  const NodeReach r[2] = {reach(f, tangent, i, c, n, flatBefore[i], p),
                          reach(f, tangent, i + 1, c, n, flatBefore[i + 1], p)};
  const Real target = std::max(r[0].now, r[1].now) - delta;  // new extent along n
  for (int q = 0; q < 2; ++q) {
    const Index k = i + q;
    if (r[q].cos == 0 || r[q].now <= target) continue;  // this end already lies within: leave it round
    Vec3 dir;
    flatteningDirection(f, tangent, k, n, dir);
    const Real ask = (r[q].now - target) / (r[q].cos * f.secRadius[k]);
    dirSum[k] += (dir.dot(f.secDir[k]) < 0 ? -ask : ask) * dir;
    f.secFlat[k] = std::min(p.mcd, std::max(f.secFlat[k], flatBefore[k] + ask));
  }
}

namespace {
// What node k's section can still lose at a gap-model contact [m]: its support along n down to the
// MCD, or (thickness) its half-thickness b = r0 (1 - eps) down to r0 (1 - MCD).
Real nodeCapacity(const Fabric& f, const Vec3Array& tangent, Index k, const Vec3& n, bool thickness, Real eps,
                  const ContactParams& p) {
  if (thickness) return f.secRadius[k] * std::max(Real(0), p.mcd - eps);
  const NodeReach r = reach(f, tangent, k, f.pos[k], n, eps, p);
  return r.now - r.min;
}
}  // namespace

Real flatteningCapacityAt(const Fabric& f, const Vec3Array& tangent, Index e, Real s, const Vec3& n, bool thickness,
                          const ContactParams& p, const std::vector<Real>* flat) {
  const std::vector<Real>& eps = flat ? *flat : f.secFlat;
  const Index i = f.elem0[e];
  return (1 - s) * nodeCapacity(f, tangent, i, n, thickness, eps[i], p) +
         s * nodeCapacity(f, tangent, i + 1, n, thickness, eps[i + 1], p);
}

void flattenAt(Fabric& f, const Vec3Array& tangent, Index e, Real s, const Vec3& n, bool thickness, Real delta,
               const ContactParams& p, const std::vector<Real>& flatBefore, Vec3Array& dirSum) {
  if (!(delta > 0)) return;
  const Index i = f.elem0[e];
  const Real cap[2] = {nodeCapacity(f, tangent, i, n, thickness, flatBefore[i], p),
                       nodeCapacity(f, tangent, i + 1, n, thickness, flatBefore[i + 1], p)};
  const Real total = (1 - s) * cap[0] + s * cap[1];
  if (!(total > 0)) return;
  for (int q = 0; q < 2; ++q) {
    const Index k = i + q;
    if (cap[q] <= 0) continue;
    Vec3 dir;
    Real c = flatteningDirection(f, tangent, k, n, dir);
    if (thickness) {  // b shrinks whatever the normal; a circular section still turns to face it
      if (c == 0) dir = f.secDir[k];
      c = 1;
    }
    if (c == 0) continue;
    // Each node gives the same share of what it has left: the section at s loses exactly delta
    // (<= total), and no node is asked for more than its capacity.
    const Real loss = std::min(Real(1), delta / total) * cap[q];
    const Real ask = loss / (c * f.secRadius[k]);
    dirSum[k] += (dir.dot(f.secDir[k]) < 0 ? -ask : ask) * dir;
    f.secFlat[k] = std::min(p.mcd, std::max(f.secFlat[k], flatBefore[k] + ask));
  }
}

void turnSections(Fabric& f, const Vec3Array& tangent, const std::vector<Real>& flatBefore, Vec3Array& dirSum) {
  for (Index k = 0; k < f.nNodes(); ++k) {
    if (dirSum[k].squaredNorm() == 0) continue;
    Vec3 d = flatBefore[k] * f.secDir[k] + dirSum[k];
    d -= d.dot(tangent[k]) * tangent[k];
    if (d.norm() > 1e-12) f.secDir[k] = d.normalized();
    dirSum[k].setZero();
  }
}

}  // namespace woven
