#include "geom/SeparatingAxis.hpp"
#include "geom/SegmentDistance.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {

// Projections shared by every axis: C = A^T B (c_ij = A_i . B_j), |C|, AD = A^T D, BD = B^T D,
// D = c_B - c_A; computed once per pair.
struct Frame {
  Mat3 C, absC;
  Vec3 AD, BD;
  Frame(const OBB& a, const OBB& b) {
    C.noalias() = a.axes.transpose() * b.axes;
    absC = C.cwiseAbs();
    const Vec3 D = b.centre - a.centre;
    AD.noalias() = a.axes.transpose() * D;
    BD.noalias() = b.axes.transpose() * D;
  }
};

// Axis k of the 15 (Eberly's table): R = |L . D| and Rsum = R0 + R1, both scaled by |L| for the edge
// axes L = A_i x B_j, and pad = the growth of Rsum when every |c_ij| is padded by kAxisEpsilon.
struct AxisTerms {
  Real R, Rsum, pad;
};
inline AxisTerms axisTerms(int k, const OBB& a, const OBB& b, const Frame& f) {
  const Vec3 &ea = a.extent, &eb = b.extent;
  const Mat3& M = f.absC;
  if (k < 3) return {std::abs(f.AD[k]), ea[k] + eb.dot(M.row(k)), kAxisEpsilon * eb.sum()};
  if (k < 6) {
    const int j = k - 3;
    return {std::abs(f.BD[j]), ea.dot(M.col(j)) + eb[j], kAxisEpsilon * ea.sum()};
  }
  const int i = (k - 6) / 3, j = (k - 6) % 3;
  const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
  return {std::abs(f.C(i1, j) * f.AD[i2] - f.C(i2, j) * f.AD[i1]),
          ea[i1] * M(i2, j) + ea[i2] * M(i1, j) + eb[j1] * M(i, j2) + eb[j2] * M(i, j1),
          kAxisEpsilon * (ea[i1] + ea[i2] + eb[j1] + eb[j2])};
}

// |A_i x B_j| = sin of the angle between the unit axes = sqrt(1 - c_ij^2).
inline Real edgeLength(int k, const Frame& f) {
  const Real c = f.C((k - 6) / 3, (k - 6) % 3);
  return std::sqrt(std::max(Real(0), 1 - c * c));
}

Vec3 axisVector(int k, const OBB& a, const OBB& b) {
  if (k < 3) return a.axis(k);
  if (k < 6) return b.axis(k - 3);
  return a.axis((k - 6) / 3).cross(b.axis((k - 6) % 3));
}

Real sgn(Real x) { return x < 0 ? -1.0 : 1.0; }

// Sutherland-Hodgman clip of a convex polygon against the half-space n.x <= d.
int clipPolygon(const Vec3* in, int n, const Vec3& nrm, Real d, Vec3* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 &p = in[i], &q = in[(i + 1) % n];
    const Real dp = nrm.dot(p) - d, dq = nrm.dot(q) - d;
    if (dp <= 0) out[m++] = p;
    if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) out[m++] = p + (q - p) * (dp / (dp - dq));
  }
  return m;
}

// Face-face (or vertex/edge-face) contact: the reference face of box R (axis r, outward normal nR)
// against the most anti-parallel face of box I; the incident face is clipped to the reference face's
// sides and the points below the reference plane are kept. onR/onI are filled per point.
int faceContact(const OBB& R, int r, const Vec3& nR, const OBB& I, BoxContactPoint* pts, bool refIsA, Real slop) {
  const Vec3 refCentre = R.centre + nR * R.extent[r];
  int j = 0;
  Real best = -1;
  for (int k = 0; k < 3; ++k) {
    const Real v = std::abs(I.axis(k).dot(nR));
    if (v > best) best = v, j = k;
  }
  const Vec3 incNormal = -sgn(I.axis(j).dot(nR)) * I.axis(j);  // faces R
  const Vec3 incCentre = I.centre + incNormal * I.extent[j];
  const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
  const Vec3 u = I.axis(j1) * I.extent[j1], v = I.axis(j2) * I.extent[j2];
  Vec3 bufA[16] = {incCentre + u + v, incCentre - u + v, incCentre - u - v, incCentre + u - v};
  Vec3 bufB[16];
  int n = 4;
  Vec3* src = bufA;
  Vec3* dst = bufB;
  for (int k = 1; k <= 2; ++k) {
    const int ax = (r + k) % 3;
    const Vec3 side = R.axis(ax);
    const Real c = side.dot(R.centre);
    n = clipPolygon(src, n, side, c + R.extent[ax], dst);
    std::swap(src, dst);
    n = clipPolygon(src, n, Vec3(-side), -c + R.extent[ax], dst);
    std::swap(src, dst);
  }
  int m = 0;
  for (int k = 0; k < n && m < 8; ++k) {
    const Real sep = (src[k] - refCentre).dot(nR);  // < 0: below the reference face
    if (sep > slop) continue;
    BoxContactPoint cp;
    const Vec3 onI = src[k], onR = src[k] - sep * nR;
    cp.onA = refIsA ? onR : onI;
    cp.onB = refIsA ? onI : onR;
    cp.depth = -sep;
    pts[m++] = cp;
  }
  return m;
}

}  // namespace

bool obbOverlap(const OBB& a, const OBB& b) {
  // Same 15 tests as axisTerms, written out so the yes/no answer costs no more than the test itself.
  const Frame f(a, b);
  const Vec3 &ea = a.extent, &eb = b.extent;
  const Mat3 M = f.absC.array() + kAxisEpsilon;
  for (int i = 0; i < 3; ++i)
    if (std::abs(f.AD[i]) > ea[i] + eb[0] * M(i, 0) + eb[1] * M(i, 1) + eb[2] * M(i, 2)) return false;
  for (int j = 0; j < 3; ++j)
    if (std::abs(f.BD[j]) > ea[0] * M(0, j) + ea[1] * M(1, j) + ea[2] * M(2, j) + eb[j]) return false;
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      if (std::abs(f.C(i1, j) * f.AD[i2] - f.C(i2, j) * f.AD[i1]) >
          ea[i1] * M(i2, j) + ea[i2] * M(i1, j) + eb[j1] * M(i, j2) + eb[j2] * M(i, j1))
        return false;
    }
  }
  return true;
}

namespace {
// The 15 axes with early out; the TD is the minimum over all of them, or with Lateral over those at
// least acos(lateralCos) away from both A0 and B0 (when there is one). Returns false if separated.
template <bool Lateral>
bool minimumAxis(const OBB& a, const OBB& b, const Frame& f, Real slop, Real lateralCos, int& best, Real& bestDepth) {
  bestDepth = INFINITY;
  best = -1;
  Real lateralDepth = INFINITY;
  int lateral = -1;
  for (int k = 0; k < 15; ++k) {
    const AxisTerms t = axisTerms(k, a, b, f);
    const Real len = k < 6 ? 1.0 : edgeLength(k, f);
    if (t.R > t.Rsum + t.pad + slop * len) return false;  // separating axis: early out
    if (len < kParallel) continue;                        // degenerate edge axis: no depth from it
    const Real depth = (t.Rsum - t.R) / len;
    if (depth < bestDepth) bestDepth = depth, best = k;   // strict: faces (tested first) win ties
    if (Lateral && depth < lateralDepth) {
      // |L.A0| and |L.B0| from C = A^T B: for L = A_i x B_j, L.A0 = (A0 x A_i).B_j and
      // L.B0 = A_i.(B_j x B0), i.e. +-c of the other two axes (0 when i = 0, resp. j = 0).
      Real la, lb;
      if (k < 3) la = k == 0, lb = f.absC(k, 0);
      else if (k < 6) la = f.absC(0, k - 3), lb = k == 3;
      else {
        const int i = (k - 6) / 3, j = (k - 6) % 3;
        la = i == 0 ? 0 : f.absC(i == 1 ? 2 : 1, j) / len;
        lb = j == 0 ? 0 : f.absC(i, j == 1 ? 2 : 1) / len;
      }
      if (la <= lateralCos && lb <= lateralCos) lateralDepth = depth, lateral = k;
    }
  }
  if (Lateral && lateral >= 0) best = lateral, bestDepth = lateralDepth;
  return true;
}
}  // namespace

BoxContact obbContact(const OBB& a, const OBB& b, Real slop, Real lateralCos, bool points) {
  BoxContact out;
  const Frame f(a, b);
  int best;
  Real bestDepth;
  const bool touching = lateralCos < 1 ? minimumAxis<true>(a, b, f, slop, lateralCos, best, bestDepth)
                                       : minimumAxis<false>(a, b, f, slop, lateralCos, best, bestDepth);
  if (!touching) return out;
  out.overlap = true;
  out.axis = best;
  out.depth = bestDepth;
  const Vec3 D = b.centre - a.centre;
  Vec3 n = axisVector(best, a, b).normalized();
  if (n.dot(D) < 0) n = -n;
  out.normal = n;
  if (!points) return out;
  if (best < 3) {
    out.nPoints = faceContact(a, best, n, b, out.points.data(), true, slop);
  } else if (best < 6) {
    out.nPoints = faceContact(b, best - 3, Vec3(-n), a, out.points.data(), false, slop);
  } else {
    const int i = (best - 6) / 3, j = (best - 6) % 3;
    Vec3 pa = a.centre, pb = b.centre;
    for (int k = 0; k < 3; ++k) {
      if (k != i) pa += sgn(a.axis(k).dot(n)) * a.extent[k] * a.axis(k);
      if (k != j) pb -= sgn(b.axis(k).dot(n)) * b.extent[k] * b.axis(k);
    }
    const SegmentClosest c = closestSegmentSegment(pa - a.extent[i] * a.axis(i), pa + a.extent[i] * a.axis(i),
                                                    pb - b.extent[j] * b.axis(j), pb + b.extent[j] * b.axis(j));
    BoxContactPoint cp;
    cp.onA = pa + (2 * c.s - 1) * a.extent[i] * a.axis(i);
    cp.onB = pb + (2 * c.t - 1) * b.extent[j] * b.axis(j);
    cp.depth = out.depth;
    out.points[0] = cp;
    out.nPoints = 1;
  }
  return out;
}

SweptContact obbFirstContact(const OBB& a, const Vec3& va, const OBB& b, const Vec3& vb, Real dt) {
  // On every (fixed) axis L the centre distance projects to s(t) = L.(D + W t), W = vb - va; the
  // projections overlap while |s(t)| <= R0 + R1. The boxes touch first at the latest entry time
  // over the 15 axes, provided it precedes the earliest exit time (Eberly, dynamic SAT).
  SweptContact out;
  const Frame f(a, b);
  const Vec3 W = vb - va;
  const Vec3 D = b.centre - a.centre;
  Real tFirst = -INFINITY, tLast = INFINITY;
  for (int k = 0; k < 15; ++k) {
    const Vec3 L = axisVector(k, a, b);
    const AxisTerms t = axisTerms(k, a, b, f);
    const Real Rsum = t.Rsum + t.pad;
    const Real s0 = L.dot(D), w = L.dot(W);
    if (w == 0) {
      if (std::abs(s0) > Rsum) return out;  // separated for all t on this axis
      continue;
    }
    Real t1 = (-Rsum - s0) / w, t2 = (Rsum - s0) / w;
    if (t1 > t2) std::swap(t1, t2);
    tFirst = std::max(tFirst, t1);
    tLast = std::min(tLast, t2);
    if (tFirst > tLast || tFirst > dt || tLast < 0) return out;
  }
  out.hit = true;
  out.time = std::max(tFirst, Real(0));
  OBB a1 = a, b1 = b;
  a1.centre += va * out.time;
  b1.centre += vb * out.time;
  const Real scale = std::max({a.extent.maxCoeff(), b.extent.maxCoeff(), 1e-300});
  out.contact = obbContact(a1, b1, 1e-9 * scale);
  return out;
}

}  // namespace woven
