#include "geom/YarnCurve.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {
// The rounded corners at CP e's two nodes: for each, the blend length over e's rest length (alpha)
// and over the other CP's (beta); 0 at a yarn's end node (no corner).
struct Corners {
  Real alpha0 = 0, beta0 = 0, alpha1 = 0, beta1 = 0;
};
inline Corners cornersOf(const Fabric& f, Index e) {
  const Yarn& y = f.yarns[f.elemYarn[e]];
  const Index k = f.elem0[e];
  const Real L = f.restLength[e];
  Corners c;
  if (e > y.firstElem) {
    const Real Lp = f.restLength[e - 1], lambda = std::min(kBlend * f.secRadius[k], kBlendMax * std::min(Lp, L));
    c.alpha0 = lambda / L, c.beta0 = lambda / Lp;
  }
  if (e + 1 < y.firstElem + y.nElems) {
    const Real Ln = f.restLength[e + 1], lambda = std::min(kBlend * f.secRadius[k + 1], kBlendMax * std::min(L, Ln));
    c.alpha1 = lambda / L, c.beta1 = lambda / Ln;
  }
  return c;
}
// The quadratic Bezier of a corner: from pa through control point c to pb, at u, with du/ds.
inline CurvePoint bezier(const Vec3& pa, const Vec3& c, const Vec3& pb, Real u, Real duds) {
  CurvePoint q;
  q.x = (1 - u) * (1 - u) * pa + 2 * u * (1 - u) * c + u * u * pb;
  q.d1 = (2 * (1 - u) * duds) * (c - pa) + (2 * u * duds) * (pb - c);
  q.d2 = (2 * duds * duds) * (pa - 2 * c + pb);
  return q;
}
}  // namespace

CurvePoint yarnCurveAt(const Fabric& f, Index e, Real s) {
  const Index k = f.elem0[e];
  const Vec3 &x0 = f.pos[k], &x1 = f.pos[k + 1];
  const Corners c = cornersOf(f, e);
  if (s < c.alpha0)  // node k's corner: u from 1/2 (the node) to 1 (where it meets this chord)
    return bezier(x0 + c.beta0 * (f.pos[k - 1] - x0), x0, x0 + c.alpha0 * (x1 - x0), 0.5 + 0.5 * s / c.alpha0,
                  0.5 / c.alpha0);
  if (s > 1 - c.alpha1)  // node k + 1's corner: u from 0 to 1/2
    return bezier(x1 + c.alpha1 * (x0 - x1), x1, x1 + c.beta1 * (f.pos[k + 2] - x1), 0.5 * (s - 1 + c.alpha1) / c.alpha1,
                  0.5 / c.alpha1);
  return {(1 - s) * x0 + s * x1, x1 - x0, Vec3::Zero()};
}

int yarnCurveWeights(const Fabric& f, Index e, Real s, Index node[3], Real w[3]) {
  const Index k = f.elem0[e];
  const Corners c = cornersOf(f, e);
  Real q[3];
  Index first;
  if (s < c.alpha0) {
    const Real u = 0.5 + 0.5 * s / c.alpha0;
    first = k - 1, q[0] = (1 - u) * (1 - u) * c.beta0, q[2] = u * u * c.alpha0, q[1] = 1 - q[0] - q[2];
  } else if (s > 1 - c.alpha1) {
    const Real u = 0.5 * (s - 1 + c.alpha1) / c.alpha1;
    first = k, q[0] = (1 - u) * (1 - u) * c.alpha1, q[2] = u * u * c.beta1, q[1] = 1 - q[0] - q[2];
  } else {
    first = k, q[0] = 1 - s, q[1] = s, q[2] = 0;
  }
  int n = 0;
  for (int j = 0; j < 3; ++j)
    if (q[j] != 0) node[n] = first + j, w[n] = q[j], ++n;
  return n;
}

bool walkAlong(const Fabric& f, YarnPlace& p, Real ds) {
  const Yarn& y = f.yarns[f.elemYarn[p.cp]];
  Real s = p.s + ds;
  // Past a node the remaining move, in arc length at rest, is carried over into the next CP.
  while (s > 1) {
    if (p.cp + 1 >= y.firstElem + y.nElems) {
      p.s = 1;
      return false;
    }
    const Real arc = (s - 1) * f.restLength[p.cp];
    ++p.cp;
    s = arc / f.restLength[p.cp];
  }
  while (s < 0) {
    if (p.cp <= y.firstElem) {
      p.s = 0;
      return false;
    }
    const Real arc = -s * f.restLength[p.cp];
    --p.cp;
    s = 1 - arc / f.restLength[p.cp];
  }
  p.s = s;
  return true;
}

Real closestStep(const Fabric& f, YarnPlace& a, YarnPlace& b, Real* distance) {
  const CurvePoint A = yarnCurveAt(f, a.cp, a.s), B = yarnCurveAt(f, b.cp, b.s);
  const Vec3 d = B.x - A.x;
  if (distance) *distance = d.norm();
  // Gradient and Hessian of |d|^2 / 2 in (s, t).
  const Real gs = -A.d1.dot(d), gt = B.d1.dot(d);
  const Real hss = A.d1.squaredNorm() - A.d2.dot(d), htt = B.d1.squaredNorm() + B.d2.dot(d), hst = -A.d1.dot(B.d1);
  const Real det = hss * htt - hst * hst;
  // Crossing curves give det ~ |A'|^2 |B'|^2 sin^2(angle); below 1e-6 of that (a twentieth of a
  // degree, or a curvature term as large as the tangents) the minimum is no point.
  if (!(det > 1e-6 * A.d1.squaredNorm() * B.d1.squaredNorm()) || !(hss > 0) || !(htt > 0)) return kNoStep;
  Real ds = -(htt * gs - hst * gt) / det, dt = -(hss * gt - hst * gs) / det;
  // A Newton step longer than half a CP leaves the cubic it was taken on: capped, both scaled alike.
  const Real big = std::max(std::abs(ds), std::abs(dt));
  if (big > 0.5) ds *= 0.5 / big, dt *= 0.5 / big;
  const Real moved = std::abs(ds) * f.restLength[a.cp] + std::abs(dt) * f.restLength[b.cp];
  if (!walkAlong(f, a, ds) || !walkAlong(f, b, dt)) return kLeftYarn;
  return moved;
}

bool closestPlaces(const Fabric& f, YarnPlace& a, YarnPlace& b, Real tol, int maxSteps) {
  for (int k = 0; k < maxSteps; ++k) {
    const Real moved = closestStep(f, a, b);
    if (moved < 0) return false;
    if (moved <= tol) return true;
  }
  return false;
}

}  // namespace woven
