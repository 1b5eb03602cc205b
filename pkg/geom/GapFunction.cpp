#include "geom/GapFunction.hpp"
#include "shape/Cylinder.hpp"
#include "bound/CPBound.hpp"
#include "geom/SegmentDistance.hpp"
#include "geom/SegmentTriangle.hpp"
#include "geom/YarnCurve.hpp"
#include "shape/Triangle.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {
constexpr Real kPi = 3.14159265358979323846;
// Below this the vector between two axis points gives no direction [m] (1e-5 of a KM2 filament).
constexpr Real kTinyDistance = 1e-15;
// Deviation of the yarn's tangent from a CP's chord up to which the tangent is used, and beyond
// which the chord is (yarnTangent) [deg].
constexpr Real kKinkYarnDeg = 15, kKinkFullDeg = 30;
// How much closer than at both ends of their shared part the axes of side-by-side pieces must come
// inside it for the closest point to join the manifold (pairGaps) [m]: below it they lie alongside.
constexpr Real kSideSkew = 0.5e-6;

inline Real support(const SectionAt& q, const Vec3& n) { return ellipseSupport(q.u, q.d, q.a, q.b, n); }

// Unit normal and signed distance of the axis points pA -> pB, on the pair's remembered side: when
// the vector has turned against `orient` the axes have passed through each other, and the distance
// counts negative along the old side. Without memory (a new pair) and without a direction (the axes
// meet), the normal of both axes oriented by the CP centres.
// Only where both points lie inside their segments: a piece that goes round the other's end
// changes sides legitimately.
void orientNormal(const Vec3& d, const Vec3* orient, bool interior, const Vec3& tA, const Vec3& tB,
                  const Vec3& centres, Vec3& n, Real& r) {
  const Real len = d.norm();
  if (len > kTinyDistance) {
    n = d / len, r = len;
    if (orient && interior && n.dot(*orient) < 0) n = -n, r = -len;
    return;
  }
  r = 0;
  if (orient) {
    n = *orient;
    return;
  }
  n = tA.cross(tB);
  n = n.norm() > 1e-9 ? Vec3(n.normalized()) : tA.unitOrthogonal();
  if (n.dot(centres) < 0) n = -n;
}

// The yarn's tangent at s along CP e: its node tangents interpolated. At a crossing node of a
// crimped yarn it is level where the chord is tilted by the crimp angle (8 degrees in KM2 706 at one
// CP per span). Where the chain is kinked (a broken end whipping, a yarn wrapped round a projectile's
// edge) the node tangents, central differences over three chords, turn far from the chord and
// faster than it: a section measured across them read a 76-degree crossing as side by side and its
// width as the contact's measure, and the gap fell by hundreds of micrometres in a few steps while
// the axes moved apart (the projection then pushed on phantom overlaps and put energy in). So the
// chord's own direction is taken where the interpolated tangent leaves it by more than
// kKinkFullDeg, blended from kKinkYarnDeg: the yarn's tangent where the chain is smooth, the CP's
// straight axis where it is not.
Vec3 yarnTangent(const Fabric& f, Index e, Real s, const Vec3Array* tangent, const Vec3& chord) {
  const Index i = f.elem0[e];
  Vec3 t = tangent ? Vec3((1 - s) * (*tangent)[i] + s * (*tangent)[i + 1])
                   : Vec3((1 - s) * yarnTangentAt(f, i) + s * yarnTangentAt(f, i + 1));
  const Real len = t.norm();
  if (!(len > 1e-9)) return chord;
  t /= len;
  if (t.dot(chord) < 0) t = -t;
  static const Real cYarn = std::cos(kKinkYarnDeg * kPi / 180), cFull = std::cos(kKinkFullDeg * kPi / 180);
  const Real c = t.dot(chord);
  if (c >= cYarn) return t;
  if (c <= cFull) return chord;
  const Real mu = (c - cFull) / (cYarn - cFull);  // 1 at kKinkYarnDeg, 0 at kKinkFullDeg
  return (mu * t + (1 - mu) * chord).normalized();
}
Vec3 yarnTangent(const Fabric& f, Index e, Real s, const Vec3Array* tangent) {
  const Index i = f.elem0[e];
  return yarnTangent(f, e, s, tangent, (f.pos[i + 1] - f.pos[i]).normalized());
}

// Direction the sections' supports are measured along. The chords' common normal n leans by the
// crimp angles (8 degrees in KM2 706 at one CP per span) where the yarns themselves are level at
// the crossing, and across a flat section (a/b up to 6) that lean alone would add 30 % to its
// support: so for crossing pieces the normal of the yarns' own tangents m = tA x tB is taken, and
// n itself where n runs far from m (a CP end pressing on a yarn's side), blended between 30 and
// 45 degrees. Side by side: n made normal to A's tangent.
Vec3 supportDirection(const Vec3& n, const Vec3& tA, const Vec3& tB, bool side) {
  if (!side) {
    Vec3 m = tA.cross(tB);
    const Real len = m.norm();
    if (len > 0.34) {  // the yarns cross at more than 20 degrees
      m /= len;
      if (m.dot(n) < 0) m = -m;
      const Real c = m.dot(n), c30 = 0.86602540378443865, c45 = 0.70710678118654752;
      if (c >= c30) return m;
      if (c > c45) return ((c - c45) / (c30 - c45) * m + (c30 - c) / (c30 - c45) * n).normalized();
      return n;
    }
  }
  const Vec3 p = n - n.dot(tA) * tA;
  return p.norm() > 1e-9 ? Vec3(p.normalized()) : n;
}

// Weight of the half-thickness in a CP pair's section measure: 1 where the yarns cross at 45
// degrees or more, 0 at kSideEnterDeg or less (side by side: the supports), linear between.
Real thicknessWeight(const Vec3& tA, const Vec3& tB) {
  static const Real lo = kSideEnterDeg * kPi / 180, hi = 45 * kPi / 180;
  // Outside the ramp the weight is 0 or 1 without the arc cosine: 1e-9 in the cosine is more than
  // 1e-9 rad in the angle there, where acos rounds within 1e-16 (the same result, bit for bit).
  static const Real cLo = std::cos(lo) + 1e-9, cHi = std::cos(hi) - 1e-9;
  const Real c = std::abs(tA.dot(tB));
  if (c <= cHi) return 1;
  if (c >= cLo) return 0;
  const Real angle = std::acos(std::min(Real(1), c));
  return std::clamp((angle - lo) / (hi - lo), Real(0), Real(1));
}

// CP e's unit chord: the stage's (ChordFrames) where given, else from the positions (the same
// expression).
inline Vec3 chordOf(const Fabric& f, Index e, const ChordFrames* chords) {
  const Index i = f.elem0[e];
  return chords ? chords->unit[e] : Vec3((f.pos[i + 1] - f.pos[i]).normalized());
}

// The section of CP e at s in the yarn's own plane (normal to yarnTangent), for the supports, in two
// parts: its tangent t and semi-axes (yarnSection), which every contact reads; its axes u, d
// (yarnFrame), which only a support across the section reads. Crossing pieces (at more than 45
// degrees: the half-thicknesses alone, fillPair) skip the second part, which was half the cost.
SectionAt yarnSection(const Fabric& f, Index e, Real s, SectionRule rule, const Vec3Array* tangent, const Vec3& chord) {
  SectionAt q;
  const SemiAxes ax = semiAxesAt(f, e, s, rule);
  q.a = ax.a, q.b = ax.b;
  q.t = yarnTangent(f, e, s, tangent, chord);
  return q;
}
void yarnFrame(const Fabric& f, Index e, Real s, const Vec3& chord, SectionAt& q) {
  const Vec3 d0 = sectionDir(f, e, s, chord);  // sectionAt's d, normal to the chord
  const Vec3 d = d0 - d0.dot(q.t) * q.t;
  q.d = d.norm() > 1e-9 ? Vec3(d.normalized()) : q.t.unitOrthogonal();
  q.u = q.t.cross(q.d);
}

// One CP-CP contact from the axis points A(s), B(t) with the sections' supports along the normal.
void fillPair(const Fabric& f, Index a, Index b, Real s, Real t, ContactKind kind, SectionRule rule, const Vec3* orient,
              bool sections, const Vec3Array* tangent, CPContact& c, const ChordFrames* chords = nullptr) {
  const Index i = f.elem0[a], j = f.elem0[b];
  const Vec3 pA = (1 - s) * f.pos[i] + s * f.pos[i + 1], pB = (1 - t) * f.pos[j] + t * f.pos[j + 1];
  const Vec3 tA = f.pos[i + 1] - f.pos[i], tB = f.pos[j + 1] - f.pos[j];
  const Vec3 centres = 0.5 * (f.pos[j] + f.pos[j + 1] - f.pos[i] - f.pos[i + 1]);
  Vec3 n;
  Real r;
  orientNormal(pB - pA, orient, s > 0 && s < 1 && t > 0 && t < 1, tA, tB, centres, n, r);
  if (sections) {
    const Vec3 chordA = chordOf(f, a, chords), chordB = chordOf(f, b, chords);
    SectionAt qa = yarnSection(f, a, s, rule, tangent, chordA), qb = yarnSection(f, b, t, rule, tangent, chordB);
    c.hDir = supportDirection(n, qa.t, qb.t, kind == ContactKind::Side);
    // Half-thicknesses where the pieces cross at more than 45 degrees, supports along hDir (widths
    // where the ribbons meet edge to edge) below 20, blended between: g must not jump where a pair
    // turns from crossing to side by side (see GapFunction.hpp).
    // A yarn folded back onto itself folds about its width (the easy way): its legs lie face to face.
    const Real lambda = f.elemYarn[a] == f.elemYarn[b] ? 1.0 : thicknessWeight(qa.t, qb.t);
    if (lambda == 1) {  // 1 b + 0 support is b exactly (a support is finite): no frames needed
      c.hA = qa.b, c.hB = qb.b;
    } else {
      yarnFrame(f, a, s, chordA, qa), yarnFrame(f, b, t, chordB, qb);
      c.hA = lambda * qa.b + (1 - lambda) * support(qa, c.hDir);
      c.hB = lambda * qb.b + (1 - lambda) * support(qb, c.hDir);
    }
    const Real H = c.hA + c.hB;
    c.hHeld = H > c.hCap ? H - c.hCap : 0.0;  // the measure memory (capMeasure)
    if (H > c.hCap) c.hA *= c.hCap / H, c.hB *= c.hCap / H;
  }
  c.cpA = a, c.cpB = b, c.kind = kind;
  c.sA = s, c.sB = t;
  c.normal = n;
  c.gap = r - c.hA - c.hB;
  c.point = pA + (c.hA + 0.5 * c.gap) * n;  // half way between the two surfaces
  c.sectional = true;
  c.boxDepth = 0, c.time = 0;
}

}  // namespace

Vec3 sectionDir(const Fabric& f, Index e, Real s, const Vec3& chord) {
  const Index i = f.elem0[e], j = i + 1;
  const Vec3& dj = f.secDir[j];
  Vec3 d = (1 - s) * f.secDir[i] + s * (f.secDir[i].dot(dj) < 0 ? Vec3(-dj) : dj);
  d -= d.dot(chord) * chord;
  return d.norm() > 1e-9 ? Vec3(d.normalized()) : chord.unitOrthogonal();
}

SectionAt sectionAt(const Fabric& f, Index e, Real s, SectionRule rule, const Vec3* chord) {
  const Index i = f.elem0[e], j = i + 1;
  SectionAt q;
  q.centre = (1 - s) * f.pos[i] + s * f.pos[j];
  q.t = chord ? *chord : Vec3((f.pos[j] - f.pos[i]).normalized());
  q.d = sectionDir(f, e, s, q.t);
  q.u = q.t.cross(q.d);
  const SemiAxes ax = semiAxesAt(f, e, s, rule);
  q.a = ax.a, q.b = ax.b;
  return q;
}

bool sideBySide(const Fabric& f, Index a, Index b, bool wasSide, const ChordFrames* chords) {
  const Vec3 tA = chords ? chords->unit[a] : Vec3((f.pos[f.elem0[a] + 1] - f.pos[f.elem0[a]]).normalized());
  const Vec3 tB = chords ? chords->unit[b] : Vec3((f.pos[f.elem0[b] + 1] - f.pos[f.elem0[b]]).normalized());
  static const Real cosEnter = std::cos(kSideEnterDeg * kPi / 180), cosLeave = std::cos(kSideLeaveDeg * kPi / 180);
  return std::abs(tA.dot(tB)) >= (wasSide ? cosLeave : cosEnter);
}

int pairGaps(const Fabric& f, Index a, Index b, bool side, SectionRule rule, const Vec3* orient, CPContact out[2],
             const Vec3Array* tangent, const SegmentClosest* closest, const ChordFrames* chords) {
  const Index i = f.elem0[a], j = f.elem0[b];
  if (side) {
    // The part of A alongside B: B's ends projected on A's axis, clipped to A.
    const Vec3 tA = f.pos[i + 1] - f.pos[i];
    const Real L2 = tA.squaredNorm();
    const Real s0 = (f.pos[j] - f.pos[i]).dot(tA) / L2, s1 = (f.pos[j + 1] - f.pos[i]).dot(tA) / L2;
    const Real lo = std::max(Real(0), std::min(s0, s1)), hi = std::min(Real(1), std::max(s0, s1));
    if (hi >= lo) {
      // Two points at the ends of the shared part carry a line contact's force and moment; a short
      // shared part (the pieces meet end to end) is one point.
      if (hi - lo <= 1e-3) {
        const Real s = 0.5 * (lo + hi);
        fillPair(f, a, b, s, alongCP(f, b, (1 - s) * f.pos[i] + s * f.pos[i + 1]), ContactKind::Side, rule, orient,
                 true, tangent, out[0], chords);
        out[0].anchor = SideAnchor::A;
        return 1;
      }
      // Each end of the shared part is held by the segment end that makes it: an end of A (where B
      // reaches past it) with B's closest point to it, or an end of B with A's closest point to it.
      // Both are vertex-segment distances of material ends, so the gap changes as the pieces move,
      // not as the shared part slides along them: skew pieces slide it along A (at 20 degrees a
      // broken piece's end moved 35 um along its neighbour a step), and a point held at its place
      // on A, with B's closest point to it, saw the axes 10-15 um closer each step than where the
      // last step's row and projection had held them apart.
      const Real ends[2] = {lo, hi};
      for (int k = 0; k < 2; ++k) {
        const Real s = ends[k];
        if (s > 0 && s < 1) {  // made by B's end: B(0) at s0, B(1) at s1
          fillPair(f, a, b, s, (k == 0) == (s0 <= s1) ? 0.0 : 1.0, ContactKind::Side, rule, orient ? orient + k : nullptr,
                   true, tangent, out[k], chords);
          out[k].anchor = SideAnchor::B;
        } else {
          fillPair(f, a, b, s, alongCP(f, b, f.pos[i + k]), ContactKind::Side, rule, orient ? orient + k : nullptr, true,
                   tangent, out[k], chords);
          out[k].anchor = SideAnchor::A;
        }
      }
      // Skew pieces whose axes come closest inside the shared part (an X at a small angle): the
      // ends do not see that approach, so the closest point (moving with the axes) takes the place
      // of the farther end. Between the ends B - A turns by the crossing: |B - A| has its minimum
      // inside when it falls at the first end and rises at the second; only then are the closest
      // points sought (most side-by-side pairs lie alongside: no extra work).
      const Vec3 v0 = out[0].normal * (out[0].gap + out[0].hA + out[0].hB);  // B - A at the ends
      const Vec3 v1 = out[1].normal * (out[1].gap + out[1].hA + out[1].hB);
      const Vec3 dv = v1 - v0;
      if (v0.dot(dv) < 0 && v1.dot(dv) > 0) {
        const SegmentClosest sc = closest ? *closest : closestSegmentSegment(f.pos[i], f.pos[i + 1], f.pos[j], f.pos[j + 1]);
        const Real r0 = v0.norm(), r1 = v1.norm();
        if (sc.s > lo && sc.s < hi && sc.distance < std::min(r0, r1) - kSideSkew) {
          const int q = r0 <= r1 ? 1 : 0;
          fillPair(f, a, b, sc.s, sc.t, ContactKind::Side, rule, orient ? orient + q : nullptr, true, tangent, out[q],
                   chords);
          out[q].anchor = SideAnchor::Closest;
        }
      }
      return 2;
    }
  }
  // Crossing pieces: the closest points of the axes. Parallel ones that do not lie alongside (end
  // to end) keep the side-by-side measure at their closest points, so that the gap does not jump
  // from the half-thickness to the width when they slide alongside.
  const SegmentClosest sc = closest ? *closest : closestSegmentSegment(f.pos[i], f.pos[i + 1], f.pos[j], f.pos[j + 1]);
  fillPair(f, a, b, sc.s, sc.t, side ? ContactKind::Side : ContactKind::Cross, rule, orient, true, tangent, out[0],
           chords);
  return 1;
}

namespace {
// The crossing's g at its held places: the lines' points (from the stencil's weights), the normal on
// the remembered side (the lines cannot pass each other's ends: the crossing hands itself back
// first), and with `sections` the half-thicknesses at the places, capped by c.hCap (the measure
// memory), else the held ones.
void measureCrossing(const Fabric& f, CPContact& c, SectionRule rule, bool sections) {
  Vec3 A = Vec3::Zero(), B = Vec3::Zero();
  for (int k = 0; k < c.nStencilA; ++k) A -= c.stencilW[k] * f.pos[c.stencilNode[k]];  // A's weights are negative
  for (int k = c.nStencilA; k < c.nStencil; ++k) B += c.stencilW[k] * f.pos[c.stencilNode[k]];
  const Vec3 d = B - A;
  const Real len = d.norm();
  Real r = 0;
  if (len > kTinyDistance) {
    const bool through = d.dot(c.normal) < 0;  // the axes have passed through each other
    c.normal = through ? Vec3(-d / len) : Vec3(d / len), r = through ? -len : len;
  }
  if (sections) {
    // The half-thicknesses whatever the direction: it only turns a still-circular section to face
    // it when it flattens (SectionFlattening), and between a crossing's lines' closest points the
    // normal is the yarns' common normal.
    c.hDir = c.normal;
    c.hA = semiAxesAt(f, c.cpA, c.sA, rule).b, c.hB = semiAxesAt(f, c.cpB, c.sB, rule).b;
    const Real H = c.hA + c.hB;
    c.hHeld = H > c.hCap ? H - c.hCap : 0.0;
    if (H > c.hCap) c.hA *= c.hCap / H, c.hB *= c.hCap / H;
  }
  c.gap = r - c.hA - c.hB;
  c.point = A + (c.hA + 0.5 * c.gap) * c.normal;  // half way between the two surfaces
}
}  // namespace

void crossingGap(const Fabric& f, Index a, Real s, Index b, Real t, SectionRule rule, const Vec3& orient,
                 CPContact& out) {
  out.cpA = a, out.cpB = b, out.sA = s, out.sB = t, out.kind = ContactKind::Crossing;
  out.normal = orient, out.sectional = true, out.hCap = INFINITY, out.boxDepth = 0, out.time = 0;
  out.crossing = -1, out.warm = 0, out.drift = 0;
  const int m = yarnCurveWeights(f, a, s, out.stencilNode, out.stencilW);
  for (int k = 0; k < m; ++k) out.stencilW[k] = -out.stencilW[k];
  out.nStencilA = static_cast<std::int8_t>(m);
  out.nStencil = static_cast<std::int8_t>(m + yarnCurveWeights(f, b, t, out.stencilNode + m, out.stencilW + m));
  measureCrossing(f, out, rule, true);
}

int contactStencil(const Fabric& f, const CPContact& c, Index node[kMaxStencil], Real w[kMaxStencil]) {
  if (c.kind == ContactKind::Crossing) {
    for (int k = 0; k < c.nStencil; ++k) node[k] = c.stencilNode[k], w[k] = c.stencilW[k];
    return c.nStencil;
  }
  node[0] = f.elem0[c.cpA], node[1] = node[0] + 1, node[2] = f.elem0[c.cpB], node[3] = node[2] + 1;
  w[0] = -(1 - c.sA), w[1] = -c.sA, w[2] = 1 - c.sB, w[3] = c.sB;
  return 4;
}

void remeasure(const Fabric& f, CPContact& c, SectionRule rule, bool sections, const Vec3Array* tangent) {
  const Index i = f.elem0[c.cpA], j = f.elem0[c.cpB];
  Real s = c.sA, t = c.sB;
  if (c.kind == ContactKind::Crossing) return measureCrossing(f, c, rule, sections);  // its places held
  if (c.kind == ContactKind::Side && c.anchor == SideAnchor::A) {
    t = alongCP(f, c.cpB, (1 - s) * f.pos[i] + s * f.pos[i + 1]);
  } else if (c.kind == ContactKind::Side && c.anchor == SideAnchor::B) {
    s = alongCP(f, c.cpA, (1 - t) * f.pos[j] + t * f.pos[j + 1]);
  } else {
    const SegmentClosest sc = closestSegmentSegment(f.pos[i], f.pos[i + 1], f.pos[j], f.pos[j + 1]);
    s = sc.s, t = sc.t;
  }
  const Vec3 orient = c.normal;
  fillPair(f, c.cpA, c.cpB, s, t, c.kind, rule, &orient, sections, tangent, c);
}

void capMeasure(CPContact& c, Real remembered) {
  const Real r = c.gap + c.hA + c.hB;  // the axes' signed distance
  c.hCap = std::max(remembered, r);
  const Real H = c.hA + c.hB;
  c.hHeld = H > c.hCap ? H - c.hCap : 0.0;
  if (!(H > c.hCap)) return;
  const Vec3 pA = c.point - (c.hA + 0.5 * c.gap) * c.normal;  // A's axis point
  c.hA *= c.hCap / H, c.hB *= c.hCap / H;
  c.gap = r - c.hCap;
  c.point = pA + (c.hA + 0.5 * c.gap) * c.normal;  // half way between the two surfaces, as fillPair
}

bool closestOnEllipse(Real a, Real b, Real px, Real py, Real& qx, Real& qy) {
  // Eberly's algorithm wants e0 >= e1 and the point in the first quadrant: swap and reflect.
  const bool swap = a < b;
  const Real e0 = swap ? b : a, e1 = swap ? a : b;
  const Real y0 = std::abs(swap ? py : px), y1 = std::abs(swap ? px : py);
  const Real g0 = (y0 / e0) * (y0 / e0) + (y1 / e1) * (y1 / e1) - 1;
  Real x0, x1;
  if (y1 > 0) {
    if (y0 > 0) {
      const Real z0 = y0 / e0, z1 = y1 / e1, r0 = (e0 / e1) * (e0 / e1);
      if (g0 != 0) {
        // Root of F(s) = (r0 z0 / (s + r0))^2 + (z1 / (s + 1))^2 - 1 by bisection: monotone in s.
        const Real n0 = r0 * z0;
        Real s0 = z1 - 1, s1 = g0 < 0 ? 0.0 : std::hypot(n0, z1) - 1, s = 0;
        for (int it = 0; it < 200; ++it) {
          s = 0.5 * (s0 + s1);
          if (s == s0 || s == s1) break;
          const Real q0 = n0 / (s + r0), q1 = z1 / (s + 1), g = q0 * q0 + q1 * q1 - 1;
          if (g > 0) s0 = s;
          else if (g < 0) s1 = s;
          else break;
        }
        x0 = r0 * y0 / (s + r0), x1 = y1 / (s + 1);
      } else {
        x0 = y0, x1 = y1;
      }
    } else {
      x0 = 0, x1 = e1;
    }
  } else {
    const Real numer0 = e0 * y0, denom0 = e0 * e0 - e1 * e1;
    if (numer0 < denom0) {
      const Real xde0 = numer0 / denom0;
      x0 = e0 * xde0, x1 = e1 * std::sqrt(std::max(Real(0), 1 - xde0 * xde0));
    } else {
      x0 = e0, x1 = 0;
    }
  }
  x0 = std::copysign(x0, swap ? py : px), x1 = std::copysign(x1, swap ? px : py);
  qx = swap ? x1 : x0, qy = swap ? x0 : x1;
  return g0 >= 0;
}

namespace {
// Sphere form: g = |c - P| - R, P the closest point of the (held) section ellipse at c's place s
// (or, h.end >= 0, at that end node: s is kept).
Real sphereGapAt(const Vec3& x0, const Vec3& x1, const Vec3& c, Real R, const BodyContact& h, Real& s, Vec3& n,
                 Vec3& P) {
  const Vec3 axis = x1 - x0;
  s = h.end >= 0 ? Real(h.end) : std::clamp((c - x0).dot(axis) / axis.squaredNorm(), Real(0), Real(1));
  const Vec3 A = x0 + s * axis, q = c - A;
  Real qx, qy;
  const Real px = q.dot(h.secU), py = q.dot(h.secD);
  const bool outside = closestOnEllipse(h.secA, h.secB, px, py, qx, qy);
  const Real along = q.dot(axis) / axis.norm();
  if (!outside && std::abs(along) > kTinyDistance) {
    // Beyond an end, within the section's outline: the closest point is on the end face (a broken
    // end's, or the next CP's that carries its own contact), straight along the axis.
    P = A + px * h.secU + py * h.secD;
    n = (c - P).normalized();
    return std::abs(along) - R;
  }
  P = A + qx * h.secU + qy * h.secD;
  const Vec3 diff = c - P;
  const Real len = diff.norm();
  if (len > kTinyDistance) {
    n = outside ? Vec3(diff / len) : Vec3(-diff / len);  // inside: out along the surface normal at P
    return (outside ? len : -len) - R;
  }
  n = (qx / (h.secA * h.secA) * h.secU + qy / (h.secB * h.secB) * h.secD).normalized();  // c on the surface
  return -R;
}

// Box form: g = (box's lowest point along n) - (node's section reach along n), n a face normal of
// the box (turning with it), the section's support along n held in h.support[node].
Real boxGapAt(const Fabric& f, Index cp, const OBB& box, const Vec3& n, const BodyContact& h, int node) {
  const Real boxMin = box.centre.dot(n) - (box.axes.transpose() * n).cwiseAbs().dot(box.extent);
  return boxMin - (f.pos[f.elem0[cp] + node].dot(n) + h.support[node]);
}

// Node k's section frame across the yarn's tangent t there (its minor axis made normal to t).
void nodeFrame(const Fabric& f, Index k, const Vec3& t, SectionRule rule, Vec3& u, Vec3& d, SemiAxes& ax) {
  d = f.secDir[k] - f.secDir[k].dot(t) * t;
  d = d.norm() > 1e-9 ? Vec3(d.normalized()) : t.unitOrthogonal();
  u = t.cross(d);
  ax = semiAxes(f.secRadius[k], f.secFlat[k], rule);
}

// Cylinder form (the box form's separating plane, shape/Cylinder.hpp): g_k = min over the part of
// y.n_k - (x_k.n_k + support_k(n_k)), n_k held in the part frame for the step. Each end section k
// takes the candidate direction (cylinderDirections of either end node) that leaves it the most
// room, its support capped by the measure memory as on a box face: for a circular section that is
// its distance to the cylinder minus its radius, exactly (the round surface has no face to share).
Real cylinderGapAt(const Fabric& f, Index cp, const RigidBody& body, int part, const Vec3& n, const Vec3& local,
                   const BodyContact& h, int node) {
  const Real partMin = body.partCentre(part).dot(n) + cylinderMinAlong(body.parts[part], local);
  return partMin - (f.pos[f.elem0[cp] + node].dot(n) + h.support[node]);
}

template <class Listed>
int cylinderGap(const Fabric& f, Index cp, const RigidBody& body, int part, SectionRule rule, BodyContact c,
                BodyContact out[2], const Vec3Array* tangent, const BodyContact* held, const Listed& listed) {
  const Index i = f.elem0[cp];
  const Mat3 A = body.partAxes(part);
  const Vec3 centre = body.partCentre(part);
  Vec3 dirs[12];
  int nd = 0;
  for (int k = 0; k < 2; ++k) nd += cylinderDirections(body.parts[part], A.transpose() * (f.pos[i + k] - centre), dirs + nd);
  int count = 0;
  for (int k = 0; k < 2; ++k) {
    Vec3 u, d;
    SemiAxes ax;
    nodeFrame(f, i + k, yarnTangent(f, cp, k, tangent), rule, u, d, ax);
    const bool heldHere = held && held->s == k;
    Real best = -INFINITY;
    for (int j = 0; j < nd; ++j) {
      const Vec3 local = dirs[j], n = A * local;
      const bool sameFace = heldHere && held->localNormal.dot(local) > 0.999;
      const Real partMin = centre.dot(n) + cylinderMinAlong(body.parts[part], local);
      const Real room = partMin - f.pos[i + k].dot(n);
      const Real full = ellipseSupport(u, d, ax.a, ax.b, n);
      const Real support = std::min(full, std::max(sameFace ? held->support[k] : ax.b, room));
      const Real g = room - support;
      if (g > best) best = g, c.normal = n, c.localNormal = local, c.support[k] = support, c.held = full - support;
    }
    c.s = k;
    c.support[1 - k] = 0;
    c.gap = best;
    c.point = f.pos[i + k] + c.support[k] * c.normal;
    if (listed(c)) out[count++] = c;
  }
  return count;
}

// Triangle form (the separating-plane form, shape/Triangle.hpp), the vertex-face and edge contacts
// of a polytope manifold (Bullet's, Box2D's): each end node over the face (its projection inside
// the triangle) is a contact along the face normal, so that a CP lying on a face is held at both
// ends, as on a box face, not at one point it could rock on; where the axis segment comes closest
// to an edge or a corner (geom/SegmentTriangle, Eberly), a contact at that point s* along the unit
// vector from the axis point to the triangle's (the plane through the triangle's closest point
// normal to it supports the triangle). A closed mesh's face (one-sided) pushes an axis behind it
// out along its outward normal, down to a section's half-width behind (deeper is the far side of a
// thin solid); a lone facet keeps the CP on the side it was on (held), else on its longer part's.
// g = min over the triangle of y.n - (x(s).n + support(s, n)), n held in the part frame and s held
// for the step: dg/dx_k = -w_k n, w = (1 - s, s), the rows of the sphere form.
template <class Listed>
int triangleGap(const Fabric& f, Index cp, const RigidBody& body, int part, SectionRule rule, BodyContact c,
                BodyContact out[2], const BodyContact* held, const BodyContact* const* heldEnds, const Listed& listed) {
  const Index i = f.elem0[cp];
  const RigidPart& q = body.parts[part];
  const Vec3 a = body.partVertex(part, 0), b = body.partVertex(part, 1), v2 = body.partVertex(part, 2);
  const Vec3 outward = (b - a).cross(v2 - a).normalized();
  const Mat3 axes = body.partAxes(part);
  const Vec3 x[2] = {f.pos[i], f.pos[i + 1]};
  const Real height[2] = {(x[0] - a).dot(outward), (x[1] - a).dot(outward)};
  // The side the CP is on: above the face (+1: pushed along the outward normal) or below, as any of
  // its contacts with the facet held it at the last step.
  const BodyContact* anyHeld = held ? held : heldEnds && heldEnds[0] ? heldEnds[0] : heldEnds ? heldEnds[1] : nullptr;
  Real side = 1;
  if (q.twoSided)
    side = anyHeld ? -(axes * anyHeld->localNormal).dot(outward)
                   : (std::abs(height[0]) >= std::abs(height[1]) ? height[0] : height[1]);
  const Vec3 faceNormal = side >= 0 ? Vec3(-outward) : outward;  // from the CP towards the triangle
  int count = 0;
  // end: the end node a face contact stands at (its own memory), -1 the edge contact
  const auto emit = [&](Real s, const Vec3& n, int end) {
    if (count == 2) return;
    const BodyContact* memory = end < 0 ? held : heldEnds ? heldEnds[end] : nullptr;
    const Vec3 local = axes.transpose() * n;
    const SectionAt sec = sectionAt(f, cp, s, rule);
    const Real room = triangleMinAlong(a, b, v2, n) - sec.centre.dot(n);
    const Real full = ellipseSupport(sec.u, sec.d, sec.a, sec.b, n);
    // The measure memory (capMeasure's rule): the section may reach into room the triangle leaves,
    // beyond its support at the last step along the same normal (new: its half-thickness).
    const bool sameFace = memory && memory->localNormal.dot(local) > 0.999;
    const Real support = std::min(full, std::max(sameFace ? memory->support[0] : sec.b, room));
    c.s = s, c.normal = n, c.localNormal = local, c.end = static_cast<std::int8_t>(end);
    c.support[0] = support, c.support[1] = 0, c.held = full - support;
    c.gap = room - support;
    c.point = sec.centre + support * n;
    if (listed(c)) out[count++] = c;
  };
  bool onFace[2];
  for (int k = 0; k < 2; ++k) {
    onFace[k] = detail::featureOf(detail::closestPointTriangleBary(x[k], a, b, v2)) == TriangleFeature::Face;
    const Real below = -side * height[k];  // how far the node lies on the far side of the face [m]
    if (onFace[k] && below > semiAxes(f.secRadius[i + k], f.secFlat[i + k], rule).a) onFace[k] = false;  // the far side
  }
  for (int k = 0; k < 2; ++k)
    if (onFace[k]) emit(k, faceNormal, k);
  if (onFace[0] && onFace[1]) return count;  // the whole axis over the face: its ends are the closest
  const SegmentTriangleClosest sc = closestSegmentTriangle(x[0], x[1], a, b, v2);
  if (sc.feature == TriangleFeature::Face && sc.distance > kTinyDistance) return count;  // at an end over the face
  if (!(sc.distance > kTinyDistance)) {
    // The axis through the triangle away from its ends over the face: pushed back along the face
    // normal from the crossing.
    if (!onFace[0] && !onFace[1]) emit(sc.s, faceNormal, -1);
    return count;
  }
  emit(sc.s, (sc.onTriangle - sc.onSegment) / sc.distance, -1);
  return count;
}

}  // namespace

int bodyGap(const Fabric& f, Index cp, const RigidBody& body, int part, Real dt, Real margin, SectionRule rule,
            BodyContact out[2], const Vec3Array* tangent, const BodyContact* held, const BodyContact* const* heldEnds) {
  const Index i = f.elem0[cp];
  // Listed when it can touch within the step: a speculative contact (Box2D), whose row lets the pair
  // close exactly its gap. The approach is bounded by the speeds, not by the normal velocity now: a
  // CP whipping at 1500 m/s past a sphere turns its closest point and normal within the step (at 4
  // CPs per span such contacts were found 15-40 um deep at the next step).
  const Real nodeSpeed = std::sqrt(std::max(f.vel[i].squaredNorm(), f.vel[i + 1].squaredNorm()));
  const auto listed = [&](const BodyContact& c) {
    return c.gap <= margin + (body.velocityAt(c.point).norm() + nodeSpeed) * dt;
  };
  BodyContact c;
  c.cp = cp, c.part = part, c.gapModel = true, c.time = 0;
  if (body.parts[part].type == RigidPart::Type::Sphere) {
    const Vec3 centre = body.partCentre(part);
    const SectionAt q = sectionAt(f, cp, alongCP(f, cp, centre), rule);
    c.secU = q.u, c.secD = q.d, c.secA = q.a, c.secB = q.b;
    c.gap = sphereGapAt(f.pos[i], f.pos[i + 1], centre, body.parts[part].radius, c, c.s, c.normal, c.point);
    // The measure memory (capMeasure's rule): the section, turned since the last step, may not
    // reach into the sphere beyond what its held frame (or, new, its half-thickness all round) does.
    BodyContact k = c;
    if (held) k.secU = held->secU, k.secD = held->secD, k.secA = held->secA, k.secB = held->secB;
    else k.secA = q.b;
    k.gap = sphereGapAt(f.pos[i], f.pos[i + 1], centre, body.parts[part].radius, k, k.s, k.normal, k.point);
    if (c.gap < std::min(k.gap, Real(0))) {
      k.held = k.gap - c.gap;
      c = k;
    }
    int count = 0;
    if (listed(c)) out[count++] = c;
    // A CP lying along the sphere (a chord of its surface) meets it where its section is thickest,
    // which need not be at c's place: a round node at one end, the other flattened to the MCD, and
    // the place clamped to the thin end. The end node whose section (the half-thickness all round,
    // the memory's claim for a section not held) leaves the least gap, if less than at c's place,
    // is a second contact, held at that node. Traced at 4 CPs per span: a broken end along a 6 mm
    // sphere sat 24 um inside it at its round node, unmeasured, until the place flipped to it.
    BodyContact e;
    Real least = c.gap;
    for (int k2 = 0; k2 < 2; ++k2) {
      if (c.s == k2) continue;  // c's place is this end already
      // The node's disk of radius b lies within b of the node: an end farther than that from
      // leaving less gap needs no section or ellipse (most candidates; 1 pm for the rounding).
      const Index node = i + k2;
      if ((centre - f.pos[node]).norm() - body.parts[part].radius - semiAxes(f.secRadius[node], f.secFlat[node], rule).b >
          least + 1e-12)
        continue;
      BodyContact t = c;
      const SectionAt qk = sectionAt(f, cp, k2, rule);
      t.end = static_cast<std::int8_t>(k2), t.held = 0;
      t.secU = qk.u, t.secD = qk.d, t.secA = qk.b, t.secB = qk.b;
      t.gap = sphereGapAt(f.pos[i], f.pos[i + 1], centre, body.parts[part].radius, t, t.s, t.normal, t.point);
      if (t.gap < least) least = t.gap, e = t;
    }
    if (e.end >= 0 && listed(e)) out[count++] = e;
    return count;
  }
  if (body.parts[part].type == RigidPart::Type::Cylinder)
    return cylinderGap(f, cp, body, part, rule, c, out, tangent, held, listed);
  if (body.parts[part].type == RigidPart::Type::Triangle) {
    // A mesh lists each CP with the many small triangles near it: those whose bounding ball lies
    // farther from the axis than the sections reach and the step closes are culled first (a point
    // to segment distance instead of the closest points' Voronoi tests).
    const Vec3 centre = (body.partVertex(part, 0) + body.partVertex(part, 1) + body.partVertex(part, 2)) / 3;
    Real ball = 0;
    for (int k = 0; k < 3; ++k) ball = std::max(ball, (body.partVertex(part, k) - centre).norm());
    const Vec3 axis = f.pos[i + 1] - f.pos[i];
    const Real s = std::clamp((centre - f.pos[i]).dot(axis) / axis.squaredNorm(), Real(0), Real(1));
    const Real apart = (centre - f.pos[i] - s * axis).norm() - ball -
                       std::max(semiAxes(f.secRadius[i], f.secFlat[i], rule).a, semiAxes(f.secRadius[i + 1], f.secFlat[i + 1], rule).a);
    const Real bodySpeed = body.vel.norm() + body.angVel.norm() * ((centre - body.pos).norm() + ball);
    if (apart > margin + (bodySpeed + nodeSpeed) * dt) return 0;
    return triangleGap(f, cp, body, part, rule, c, out, held, heldEnds, listed);
  }
  // The face of the box that leaves the CP the most room (the separating-axis choice among the
  // box's faces), then one contact per end section: a level CP under a face is held at both ends.
  const OBB box = body.partBox(part);
  Vec3 u[2], d[2];
  SemiAxes ax[2];
  for (int k = 0; k < 2; ++k) nodeFrame(f, i + k, yarnTangent(f, cp, k, tangent), rule, u[k], d[k], ax[k]);
  // The measure memory (capMeasure's rule), on every face: each end section's support may grow
  // only into the room the box leaves, beyond its support at the last step on the same face (a new
  // contact, or another face: its half-thickness). Then the face that leaves the CP the most room.
  Real best = -INFINITY, heldBack[2] = {0, 0};
  for (int j = 0; j < 6; ++j) {
    const Vec3 n = (j < 3 ? 1.0 : -1.0) * box.axes.col(j % 3);
    const bool sameFace = held && held->localNormal.dot(box.axes.transpose() * n) > 0.999;
    const Real boxMin = box.centre.dot(n) - (box.axes.transpose() * n).cwiseAbs().dot(box.extent);
    BodyContact h;
    Real full[2];
    for (int k = 0; k < 2; ++k) {
      const Real room = boxMin - f.pos[i + k].dot(n);
      full[k] = ellipseSupport(u[k], d[k], ax[k].a, ax[k].b, n);
      h.support[k] = std::min(full[k], std::max(sameFace ? held->support[k] : ax[k].b, room));
    }
    const Real g = std::min(boxGapAt(f, cp, box, n, h, 0), boxGapAt(f, cp, box, n, h, 1));
    if (g > best) {
      best = g, c.normal = n, c.support[0] = h.support[0], c.support[1] = h.support[1];
      heldBack[0] = full[0] - h.support[0], heldBack[1] = full[1] - h.support[1];
    }
  }
  c.localNormal = box.axes.transpose() * c.normal;
  int count = 0;
  for (int k = 0; k < 2; ++k) {
    c.s = k;
    c.held = heldBack[k];
    c.gap = boxGapAt(f, cp, box, c.normal, c, k);
    // On the line through the node along n (the support is held: the arm of the body's row is then
    // exactly the gradient of g in the body's rotation).
    c.point = f.pos[i + k] + c.support[k] * c.normal;
    if (listed(c)) out[count++] = c;
  }
  return count;
}

void remeasureBody(const Fabric& f, const RigidBody& body, BodyContact& c) {
  const Index i = f.elem0[c.cp];
  if (body.parts[c.part].type == RigidPart::Type::Sphere) {
    Vec3 P;
    c.gap = sphereGapAt(f.pos[i], f.pos[i + 1], body.partCentre(c.part), body.parts[c.part].radius, c, c.s, c.normal, P);
    c.point = P;
    return;
  }
  if (body.parts[c.part].type == RigidPart::Type::Cylinder) {
    c.normal = body.partAxes(c.part) * c.localNormal;
    const int node = c.s > 0.5 ? 1 : 0;
    c.gap = cylinderGapAt(f, c.cp, body, c.part, c.normal, c.localNormal, c, node);
    c.point = f.pos[i + node] + c.support[node] * c.normal;
    return;
  }
  if (body.parts[c.part].type == RigidPart::Type::Triangle) {
    c.normal = body.partAxes(c.part) * c.localNormal;
    const Vec3 x = (1 - c.s) * f.pos[i] + c.s * f.pos[i + 1];
    const Real corner =
        triangleMinAlong(body.partVertex(c.part, 0), body.partVertex(c.part, 1), body.partVertex(c.part, 2), c.normal);
    c.gap = corner - x.dot(c.normal) - c.support[0];
    c.point = x + c.support[0] * c.normal;
    return;
  }
  const OBB box = body.partBox(c.part);
  c.normal = box.axes * c.localNormal;
  const int node = c.s > 0.5 ? 1 : 0;
  c.gap = boxGapAt(f, c.cp, box, c.normal, c, node);
  c.point = f.pos[i + node] + c.support[node] * c.normal;
}

}  // namespace woven
