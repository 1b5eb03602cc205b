#include "geom/CPContact.hpp"
#include "geom/SeparatingAxis.hpp"
#include "geom/SegmentDistance.hpp"
#include <cmath>

namespace woven {

namespace {
void fill(const Fabric& f, Index a, Index b, const BoxContact& c, CPContact& out) {
  out.cpA = a, out.cpB = b;
  out.normal = c.normal;
  Vec3 p = Vec3::Zero();
  for (int k = 0; k < c.nPoints; ++k) p += 0.5 * (c.points[k].onA + c.points[k].onB);
  if (c.nPoints > 0) p /= c.nPoints;
  else p = 0.5 * (f.pos[f.elem0[a]] + f.pos[f.elem0[b]]);
  out.point = p;
  out.sA = alongCP(f, a, p), out.sB = alongCP(f, b, p);
}
}  // namespace

SectionLine sectionSurfaceAlong(const Fabric& f, Index e, const Vec3& p, const Vec3& m, SectionRule rule, Real& lambda) {
  const Index i = f.elem0[e], j = i + 1;
  const Vec3 axis = f.pos[j] - f.pos[i];
  if (std::abs(m.dot(axis)) > kLateralCos * axis.norm()) return SectionLine::Axial;
  // A point beyond an end face (by more than a tenth of the CP: the joint's end section) lies on
  // the next CP of the yarn, which has its own contacts.
  const Real sRaw = (p - f.pos[i]).dot(axis) / axis.squaredNorm();
  if (sRaw < -0.1 || sRaw > 1.1) return SectionLine::Beside;
  const Real s = std::min(Real(1), std::max(Real(0), sRaw));
  const Vec3 t = axis.normalized();
  const Vec3 c = (1 - s) * f.pos[i] + s * f.pos[j];
  const Vec3& dj = f.secDir[j];
  Vec3 d = (1 - s) * f.secDir[i] + s * (f.secDir[i].dot(dj) < 0 ? Vec3(-dj) : dj);
  d -= d.dot(t) * t;
  if (d.norm() < 1e-9) return SectionLine::Axial;
  d.normalize();
  const Vec3 u = t.cross(d);
  const SemiAxes si = semiAxes(f.secRadius[i], f.secFlat[i], rule), sj = semiAxes(f.secRadius[j], f.secFlat[j], rule);
  const Real ia2 = 1 / std::pow((1 - s) * si.a + s * sj.a, 2), ib2 = 1 / std::pow((1 - s) * si.b + s * sj.b, 2);
  const Vec3 q = p - c;
  const Real px = q.dot(u), py = q.dot(d), mx = m.dot(u), my = m.dot(d);
  // (px + l mx)^2/a^2 + (py + l my)^2/b^2 = 1
  const Real A = mx * mx * ia2 + my * my * ib2, B = 2 * (px * mx * ia2 + py * my * ib2),
             C = px * px * ia2 + py * py * ib2 - 1;
  const Real disc = B * B - 4 * A * C;
  if (disc < 0) return SectionLine::Beside;
  lambda = (-B + std::sqrt(disc)) / (2 * A);  // A > 0: m is within 45 degrees of the section plane
  return SectionLine::Hit;
}

bool cpContactStatic(const Fabric& f, const std::vector<OBB>& bounds, Index a, Index b, Real margin, SectionRule rule,
                     CPContact& out) {
  const BoxContact c = obbContact(bounds[a], bounds[b], 0, kLateralCos, false);  // the point comes from the axes
  if (!c.overlap) return false;
  out.cpA = a, out.cpB = b;
  out.sectional = false;
  // The deepest place between two yarn pieces is where their axes come closest: measure there.
  const Vec3 &a0 = f.pos[f.elem0[a]], &a1 = f.pos[f.elem0[a] + 1], &b0 = f.pos[f.elem0[b]], &b1 = f.pos[f.elem0[b] + 1];
  const SegmentClosest sc = closestSegmentSegment(a0, a1, b0, b1);
  const Vec3 onA = a0 + sc.s * (a1 - a0), onB = b0 + sc.t * (b1 - b0);
  // The SAT orients its axis by the boxes' centres; two tilted pieces of crimped yarn can lie the
  // other way round where their axes pass each other (A's centre above B's, A below B at the
  // crossing). The side that counts is the local one: with the box's sign, the impulse would push
  // B through A, and the depth below would be measured to the far sides of the sections.
  out.normal = (onB - onA).dot(c.normal) < 0 ? Vec3(-c.normal) : c.normal;
  out.sA = sc.s, out.sB = sc.t;
  out.point = 0.5 * (onA + onB);
  Real la, lb;  // A's surface at p + la n, B's at p - lb n
  const SectionLine ha = sectionSurfaceAlong(f, a, out.point, out.normal, rule, la);
  const SectionLine hb = sectionSurfaceAlong(f, b, out.point, Vec3(-out.normal), rule, lb);
  if (ha == SectionLine::Axial || hb == SectionLine::Axial) out.gap = 2 * margin - c.depth;  // end-on: boxes
  else if (ha == SectionLine::Beside || hb == SectionLine::Beside) out.gap = 2 * margin;      // box corners only
  else out.gap = std::max(-(la + lb), 2 * margin - c.depth), out.sectional = true;  // the boxes bound the bodies
  out.boxDepth = c.depth;
  out.time = 0;
  return true;
}

bool cpContactMoving(const Fabric& f, const std::vector<OBB>& bounds, Index a, Index b, Real dt, Real margin,
                     CPContact& out) {
  // A CP that turns moves its ends at different velocities; a point on it moves at a mix of the
  // two. Translating each box with either end's velocity brackets that: the earliest hit counts.
  SweptContact s;
  Vec3 va = Vec3::Zero(), vb = Vec3::Zero();
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const Vec3& ua = f.vel[f.elem0[a] + i];
      const Vec3& ub = f.vel[f.elem0[b] + j];
      const SweptContact t = obbFirstContact(bounds[a], ua, bounds[b], ub, dt);
      if (t.hit && t.contact.overlap && (!s.hit || t.time < s.time)) s = t, va = ua, vb = ub;
    }
  if (!s.hit) return false;
  fill(f, a, b, s.contact, out);
  const Real closing = std::max(Real(0), -(vb - va).dot(out.normal)) * s.time;
  out.gap = 2 * margin + closing;
  out.boxDepth = s.contact.depth;
  out.sectional = false;
  out.time = s.time;
  return true;
}

}  // namespace woven
