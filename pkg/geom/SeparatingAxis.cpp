#include "geom/SeparatingAxis.hpp"
#include "geom/SegmentDistance.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {

// Edge axes L = A_i x B_j come in two forms (Eberly's table and an exact one).
//
// Eberly's closed forms take everything from C = A^T B: with c_ij (absolute error ~3u, u = 1.1e-16)
// and A, B orthonormal to a few u, L.D, the radii r_A + r_B and |L| = |(c_i1j, c_i2j)| (the cross
// product's length in A's frame, not sqrt(1 - c_ij^2), whose relative error is u/|L|^2) all carry
// absolute errors of about 10u S, S = |D| + sum of the half extents. The depth (r_A + r_B - |L.D|)/|L|
// is thus off by ~10u S/|L|, harmless for a well-tilted pair but 1e-7 S at |L| = 1e-9.
//
// So edges closer to parallel than kExactSine (|c_ij| > kExactCos) are evaluated on the actual
// cross product in world coordinates: each component by Kahan's a*b - c*d with one FMA, correct to
// 2u of itself however small (Jeannerod, Louvet & Muller, Math. Comp. 82, 2013), then the radii as
// sums of e_k |L.A_k| over the actual axis vectors (L.A_i = L.B_j = 0 exactly). Every term is then
// within ~3u |L| S and the depth within ~10u S at any |L|. Above the threshold Eberly's form is
// within 10u S/0.1 = 1.1e-14 S, far inside the allowance kAxisEpsilon = 1e-12 and the oracle test's
// 1e-15 m on millimetre boxes (tests/cpp/test_sat_oracle.cpp: worst 0.5 % of that at 0.1, 2 % with
// the threshold at 0.01, one failure in 1e5 pairs at 1e-4), at a fraction of the cost (no cross
// product, no FMA). Random orientations put 0.5 % of the edge axes below 0.1; crimped warp/weft
// crossings (bench_sat's) one pair in five.
constexpr Real kExactSine = 0.1;
constexpr Real kExactCos = 0.99498743710661995;  // sqrt(1 - kExactSine^2)

// An edge-edge contact point pair must meet at depth*normal within this fraction of the boxes' size
// (sum of the six half extents); otherwise (face/edge ties, near-parallel edges, where the support
// edges or their closest points are ill-defined) the points come from clipping instead.
constexpr Real kPointTolerance = 1e-10;

// Kahan's difference of products a*b - c*d: the FMA recovers the rounding error of c*d exactly.
inline Real diffOfProducts(Real a, Real b, Real c, Real d) {
  const Real cd = c * d;
  return std::fma(a, b, -cd) + std::fma(-c, d, cd);
}
inline Vec3 accurateCross(const Vec3& u, const Vec3& v) {
  return Vec3(diffOfProducts(u.y(), v.z(), u.z(), v.y()), diffOfProducts(u.z(), v.x(), u.x(), v.z()),
              diffOfProducts(u.x(), v.y(), u.y(), v.x()));
}

// Projections shared by every axis: C = A^T B (c_ij = A_i . B_j), |C|, D = c_B - c_A, AD = A^T D,
// BD = B^T D, and the allowance `pad` = kAxisEpsilon * (sum of both boxes' half extents) [m].
struct Frame {
  Mat3 C, absC;
  Vec3 D, AD, BD;
  Real pad;
  Frame(const OBB& a, const OBB& b) {
    C.noalias() = a.axes.transpose() * b.axes;
    absC = C.cwiseAbs();
    D = b.centre - a.centre;
    AD.noalias() = a.axes.transpose() * D;
    BD.noalias() = b.axes.transpose() * D;
    pad = kAxisEpsilon * (a.extent.sum() + b.extent.sum());
  }
};

// Axis k of the 15, unnormalised: s = L.D, Rsum = r_A + r_B (both boxes' projection radii), len = |L|
// (1 on faces; 0 marks an edge axis left out), la = |L.A0|, lb = |L.B0| (for lateralCos). The depth
// along the unit axis is (Rsum - |s|)/len; the boxes are apart on it when |s| - Rsum > len * pad.
struct AxisTerms {
  Real s, Rsum, len, la, lb;
};

inline AxisTerms faceTerms(int k, const OBB& a, const OBB& b, const Frame& f) {
  const Mat3& M = f.absC;
  if (k < 3) return {f.AD[k], a.extent[k] + b.extent.dot(M.row(k)), 1, Real(k == 0), M(k, 0)};
  const int j = k - 3;
  return {f.BD[j], a.extent.dot(M.col(j)) + b.extent[j], 1, M(0, j), Real(j == 0)};
}

// Eberly's closed form for A_i x B_j, |c_ij| <= kExactCos. In A's frame L = e_i x C.col(j).
inline AxisTerms eberlyEdge(int i, int j, const OBB& a, const OBB& b, const Frame& f) {
  const Vec3 &ea = a.extent, &eb = b.extent;
  const Mat3& M = f.absC;
  const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
  const Real c1 = f.C(i1, j), c2 = f.C(i2, j);
  // L.A0 and L.B0 are +-c of the other two axes (0 when i = 0, resp. j = 0)
  return {c1 * f.AD[i2] - c2 * f.AD[i1], ea[i1] * M(i2, j) + ea[i2] * M(i1, j) + eb[j1] * M(i, j2) + eb[j2] * M(i, j1),
          std::sqrt(c1 * c1 + c2 * c2), i == 0 ? 0 : M(i == 1 ? 2 : 1, j), j == 0 ? 0 : M(i, j == 1 ? 2 : 1)};
}

// The exact form for a near-parallel A_i x B_j (|c_ij| > kExactCos); L is returned for the normal and
// the moving test. Out of line: it keeps the loops over Eberly's forms small. Cloned for CPUs with FMA
// (picked at load time), where std::fma is one instruction instead of a call to libm. Not under
// GCC's ThreadSanitizer: the clones' ifunc resolver runs while the program is relocated, before the
// TSan runtime starts, and its instrumented entry crashes there (scripts/tsan.sh gcc).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
#define WOVEN_FMA_CLONES [[gnu::target_clones("fma", "default")]]
#else
#define WOVEN_FMA_CLONES
#endif
WOVEN_FMA_CLONES [[gnu::noinline]] Vec3 exactCross(const Vec3& u, const Vec3& v) { return accurateCross(u, v); }
WOVEN_FMA_CLONES [[gnu::noinline]] AxisTerms exactEdge(int i, int j, const OBB& a, const OBB& b, const Vec3& D, Vec3& L) {
  L = accurateCross(a.axis(i), b.axis(j));
  const Real len = L.norm();
  if (!(len >= kParallel)) return {0, 0, 0, 0, 0};
  const Vec3 pa = (a.axes.transpose() * L).cwiseAbs(), pb = (b.axes.transpose() * L).cwiseAbs();
  Real Rsum = 0;
  for (int k = 0; k < 3; ++k) Rsum += (k != i ? a.extent[k] * pa[k] : 0) + (k != j ? b.extent[k] * pb[k] : 0);
  return {L.dot(D), Rsum, len, i == 0 ? 0 : pa[0], j == 0 ? 0 : pb[0]};
}
#undef WOVEN_FMA_CLONES

// Unit axis k (not oriented), the cross product exact where it is near-parallel.
Vec3 unitAxis(int k, const OBB& a, const OBB& b, const Frame& f) {
  if (k < 3) return a.axis(k);
  if (k < 6) return b.axis(k - 3);
  const int i = (k - 6) / 3, j = (k - 6) % 3;
  const Vec3 L = f.absC(i, j) > kExactCos ? exactCross(a.axis(i), b.axis(j)) : Vec3(a.axis(i).cross(b.axis(j)));
  return L / L.norm();
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

// Contact points by clipping (Gottschalk's and ODE's box-box manifold): the incident face of box I
// (the one most anti-parallel to n, the unit normal from R to I) is clipped to the prism that the
// reference face r of R sweeps along n, and each vertex left is lifted along n onto the reference
// plane: onI is the vertex on I, onR the lifted point on R, depth the distance lifted. For a face
// axis n is the face normal and the prism's sides are R's side faces. For any other n (degenerate
// edge-edge contacts) the sides contain n, so the points still lie on both surfaces, and as
// depth <= the overlap on n, each lies within `depth` of the other box. The prism is grown by `grow`:
// boxes that touch within the allowance sideways too (corner to corner) still give their point.
// Points shallower than `keep` are dropped; depths are reported no lower than -slop.
int clipContact(const OBB& R, int r, const Vec3& n, bool faceAxis, const OBB& I, BoxContactPoint* pts, bool refIsA,
                Real keep, Real slop, Real grow) {
  const Vec3 nR = sgn(R.axis(r).dot(n)) * R.axis(r);  // outward normal of the reference face
  const Real plane = nR.dot(R.centre) + R.extent[r], lift = 1 / nR.dot(n);  // nR.n >= 1/sqrt(3)
  int j = 0;
  Real best = -1;
  for (int k = 0; k < 3; ++k) {
    const Real v = std::abs(I.axis(k).dot(n));
    if (v > best) best = v, j = k;
  }
  const Vec3 incNormal = -sgn(I.axis(j).dot(n)) * I.axis(j);  // faces R
  const Vec3 incCentre = I.centre + incNormal * I.extent[j];
  const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
  const Vec3 u = I.axis(j1) * I.extent[j1], v = I.axis(j2) * I.extent[j2];
  Vec3 bufA[16] = {incCentre + u + v, incCentre - u + v, incCentre - u - v, incCentre + u - v};
  Vec3 bufB[16];
  int m = 4;
  Vec3* src = bufA;
  Vec3* dst = bufB;
  const Vec3 faceCentre = R.centre + R.extent[r] * nR;
  for (int k = 1; k <= 2; ++k) {
    const int p = (r + k) % 3, q = (r + 3 - k) % 3;  // the sides +-e_p A_p, along A_q
    Vec3 side = R.axis(p);
    if (!faceAxis) side = R.axis(q).cross(n), side *= sgn(side.dot(R.axis(p)));
    const Real c = side.dot(faceCentre), h = (R.extent[p] + grow) * side.dot(R.axis(p));
    m = clipPolygon(src, m, side, c + h, dst);
    std::swap(src, dst);
    m = clipPolygon(src, m, Vec3(-side), -c + h, dst);
    std::swap(src, dst);
  }
  int out = 0;
  for (int k = 0; k < m && out < 8; ++k) {
    const Real depth = (plane - nR.dot(src[k])) * lift;  // > 0: below the reference face
    if (!(depth >= keep)) continue;
    BoxContactPoint cp;
    const Vec3 onI = src[k], onR = src[k] + depth * n;
    cp.onA = refIsA ? onR : onI;
    cp.onB = refIsA ? onI : onR;
    cp.depth = std::max(depth, -slop);
    pts[out++] = cp;
  }
  return out;
}

}  // namespace

bool obbOverlap(const OBB& a, const OBB& b) {
  // Same 15 tests as obbContact, written out so the yes/no answer costs no more than the test itself.
  const Frame f(a, b);
  const Vec3 &ea = a.extent, &eb = b.extent;
  const Mat3& M = f.absC;
  for (int i = 0; i < 3; ++i)
    if (std::abs(f.AD[i]) > ea[i] + eb[0] * M(i, 0) + eb[1] * M(i, 1) + eb[2] * M(i, 2) + f.pad) return false;
  for (int j = 0; j < 3; ++j)
    if (std::abs(f.BD[j]) > ea[0] * M(0, j) + ea[1] * M(1, j) + ea[2] * M(2, j) + eb[j] + f.pad) return false;
  // Eberly's gap (scaled by |L|) is off by at most ~30u (sum e + |D|) however near parallel the edges:
  // below -sure = -1e-13 (sum e + |AD|_1) neither it nor the exact form can say apart. Most axes of
  // overlapping boxes are there, so one comparison decides them; near-parallel axes above it are left
  // to the exact form (after the loop, which so has no call in it).
  const Real pad2 = f.pad * f.pad, sure = 1e-13 * (ea.sum() + eb.sum() + f.AD.cwiseAbs().sum());
  unsigned exact = 0;
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const Real c1 = f.C(i1, j), c2 = f.C(i2, j);
      const Real gap = std::abs(c1 * f.AD[i2] - c2 * f.AD[i1]) -
                       (ea[i1] * M(i2, j) + ea[i2] * M(i1, j) + eb[j1] * M(i, j2) + eb[j2] * M(i, j1));
      if (gap <= -sure) continue;
      if (M(i, j) > kExactCos) exact |= 1u << (3 * i + j);
      else if (gap > 0 && gap * gap > (c1 * c1 + c2 * c2) * pad2) return false;  // gap > |L| pad, no root
    }
  }
  for (; exact; exact &= exact - 1) {
    const int k = __builtin_ctz(exact);
    Vec3 L;
    const AxisTerms t = exactEdge(k / 3, k % 3, a, b, f.D, L);
    if (std::abs(t.s) - t.Rsum > t.len * f.pad) return false;
  }
  return true;
}

namespace {
// The 15 axes with early out; the TD is the minimum over all of them, or with Lateral over those at
// least acos(lateralCos) away from both A0 and B0 (when there is one). Returns false if separated.
// `along` is L.D of the axis kept (its sign orients the normal).
template <bool Lateral>
bool minimumAxis(const OBB& a, const OBB& b, const Frame& f, Real slop, Real lateralCos, int& best, Real& bestDepth,
                 Real& along) {
  bestDepth = INFINITY;
  best = -1;
  Real lateralDepth = INFINITY, lateralAlong = 0;
  int lateral = -1;
  const Real allowance = f.pad + slop;
  // false if axis k separates; depth = -gap/len compared as -gap < best * len: no division per axis
  auto consider = [&](int k, const AxisTerms& t) {
    const Real gap = std::abs(t.s) - t.Rsum;
    if (gap > t.len * allowance) return false;  // separating axis: early out
    if (-gap < bestDepth * t.len) bestDepth = -gap / t.len, best = k, along = t.s;  // strict: faces win ties
    if (Lateral && -gap < lateralDepth * t.len && t.la <= lateralCos * t.len && t.lb <= lateralCos * t.len)
      lateralDepth = -gap / t.len, lateral = k, lateralAlong = t.s;
    return true;
  };
  for (int k = 0; k < 6; ++k)
    if (!consider(k, faceTerms(k, a, b, f))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Vec3 L;
      const AxisTerms t = f.absC(i, j) > kExactCos ? exactEdge(i, j, a, b, f.D, L) : eberlyEdge(i, j, a, b, f);
      if (t.len == 0) continue;  // exactly parallel edges: not an axis
      if (!consider(6 + 3 * i + j, t)) return false;
    }
  if (Lateral && lateral >= 0) best = lateral, bestDepth = lateralDepth, along = lateralAlong;
  return true;
}
}  // namespace

BoxContact obbContact(const OBB& a, const OBB& b, Real slop, Real lateralCos, bool points) {
  BoxContact out;
  const Frame f(a, b);
  int best;
  Real bestDepth, along = 0;
  const bool touching = lateralCos < 1 ? minimumAxis<true>(a, b, f, slop, lateralCos, best, bestDepth, along)
                                       : minimumAxis<false>(a, b, f, slop, lateralCos, best, bestDepth, along);
  if (!touching) return out;
  out.overlap = true;
  out.axis = best;
  out.depth = std::max(bestDepth, -slop);  // within the allowance of touching: touching
  const Vec3 n = sgn(along) * unitAxis(best, a, b, f);
  out.normal = n;
  if (!points) return out;
  // Points no shallower than the TD itself (which may lie within the allowance below -slop).
  const Real keep = std::min(bestDepth, -slop) - f.pad, grow = slop + 2 * f.pad;
  if (best < 3) {
    out.nPoints = clipContact(a, best, n, true, b, out.points.data(), true, keep, slop, grow);
    return out;
  }
  if (best < 6) {
    out.nPoints = clipContact(b, best - 3, -n, true, a, out.points.data(), false, keep, slop, grow);
    return out;
  }
  // Edge-edge: the closest points of the two support edges (Eberly). When the support is not an
  // edge (a face/edge tie, sign(A_k.n) ~ 0) or the edges are too near parallel for the closest points
  // to be defined, they do not meet at depth*n: then clip along n as for a face, from the face most
  // aligned with n.
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
  // onA - onB = depth*n puts onA within depth of B and onB within depth of A: the contact is sound.
  if ((cp.onA - cp.onB - bestDepth * n).norm() <= kPointTolerance * (a.extent.sum() + b.extent.sum())) {
    out.points[0] = cp;
    out.nPoints = 1;
    return out;
  }
  const Vec3 an = (a.axes.transpose() * n).cwiseAbs(), bn = (b.axes.transpose() * n).cwiseAbs();
  int ka, kb;
  an.maxCoeff(&ka), bn.maxCoeff(&kb);
  out.nPoints = an[ka] >= bn[kb] ? clipContact(a, ka, n, false, b, out.points.data(), true, keep, slop, grow)
                                 : clipContact(b, kb, -n, false, a, out.points.data(), false, keep, slop, grow);
  return out;
}

SweptContact obbFirstContact(const OBB& a, const Vec3& va, const OBB& b, const Vec3& vb, Real dt) {
  // On every (fixed) axis L the centre distance projects to s(t) = L.(D + W t), W = vb - va; the
  // projections overlap while |s(t)| <= R0 + R1 (+ the allowance, as in the static test). The boxes
  // touch first at the latest entry time over the 15 axes, provided it precedes the earliest exit
  // time (Eberly, dynamic SAT). s, w and the radii are all scaled by the same |L| (the same terms as
  // obbContact), so the times are those of the unit axis. The yes/no answer uses the allowance; the
  // time is the exact boxes' (no allowance) when they do meet, so it is exact to round-off instead
  // of early by kAxisEpsilon * size / speed.
  SweptContact out;
  const Frame f(a, b);
  const Vec3 W = vb - va;
  const Vec3 AW = a.axes.transpose() * W, BW = b.axes.transpose() * W;
  Real tFirst = -INFINITY, tLast = INFINITY, exactFirst = -INFINITY, exactLast = INFINITY;
  bool exactApart = false;  // the boxes without the allowance are apart on an axis they do not move along
  for (int k = 0; k < 15; ++k) {
    AxisTerms t;
    Real w;
    if (k < 6) {
      t = faceTerms(k, a, b, f);
      w = k < 3 ? AW[k] : BW[k - 3];
    } else {
      const int i = (k - 6) / 3, j = (k - 6) % 3;
      if (f.absC(i, j) > kExactCos) {
        Vec3 L;
        t = exactEdge(i, j, a, b, f.D, L);
        if (t.len == 0) continue;
        w = L.dot(W);
      } else {
        t = eberlyEdge(i, j, a, b, f);
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        w = f.C(i1, j) * AW[i2] - f.C(i2, j) * AW[i1];
      }
    }
    const Real Rsum = t.Rsum + t.len * f.pad, s0 = t.s;
    if (w == 0) {
      if (std::abs(s0) > Rsum) return out;  // separated for all t on this axis
      exactApart |= std::abs(s0) > t.Rsum;
      continue;
    }
    Real t1 = (-Rsum - s0) / w, t2 = (Rsum - s0) / w, e1 = (-t.Rsum - s0) / w, e2 = (t.Rsum - s0) / w;
    if (t1 > t2) std::swap(t1, t2), std::swap(e1, e2);
    tFirst = std::max(tFirst, t1);
    tLast = std::min(tLast, t2);
    exactFirst = std::max(exactFirst, e1);
    exactLast = std::min(exactLast, e2);
    if (tFirst > tLast || tFirst > dt || tLast < 0) return out;
  }
  out.hit = true;
  const bool meet = !exactApart && exactFirst <= exactLast && exactFirst <= dt && exactLast >= 0;
  out.time = std::max(meet ? exactFirst : tFirst, Real(0));
  OBB a1 = a, b1 = b;
  a1.centre += va * out.time;
  b1.centre += vb * out.time;
  const Real scale = std::max({a.extent.maxCoeff(), b.extent.maxCoeff(), 1e-300});
  out.contact = obbContact(a1, b1, 1e-9 * scale);
  return out;
}

}  // namespace woven
