#include "geom/BodyContact.hpp"
#include "geom/CPContact.hpp"
#include "geom/SeparatingAxis.hpp"
#include <cmath>

namespace woven {

namespace {
Vec3 meanPoint(const BoxContact& c, const Vec3& fallback) {
  if (c.nPoints == 0) return fallback;
  Vec3 p = Vec3::Zero();
  for (int k = 0; k < c.nPoints; ++k) p += 0.5 * (c.points[k].onA + c.points[k].onB);
  return p / c.nPoints;
}

// Separation along n (from the CP towards the box) of the CP's elliptic cylinder (the hull of its two
// end sections) and the box: the box's lowest point along n minus the CP's highest [m]. The CP's OBB
// fills the thin edges of a flat, tilted section (up to 35 um too deep for a KM2 section turned by
// 45 degrees), so the SAT gives the normal and the sections give the depth, as for CP-CP contacts.
Real sectionGap(const Fabric& f, Index cp, const OBB& box, const Vec3& n, SectionRule rule) {
  const Index i = f.elem0[cp];
  const Vec3 t = (f.pos[i + 1] - f.pos[i]).normalized();
  Real cpMax = -INFINITY;
  for (Index k : {i, i + 1}) {
    Vec3 d = f.secDir[k] - f.secDir[k].dot(t) * t;
    const Real len = d.norm();
    d = len > 1e-9 ? Vec3(d / len) : Vec3(t.unitOrthogonal());
    const SemiAxes ax = semiAxes(f.secRadius[k], f.secFlat[k], rule);
    cpMax = std::max(cpMax, f.pos[k].dot(n) + ellipseSupport(t.cross(d), d, ax.a, ax.b, n));
  }
  const Real boxMin = box.centre.dot(n) - (box.axes.transpose() * n).cwiseAbs().dot(box.extent);
  return boxMin - cpMax;
}

bool boxContact(const Fabric& f, const OBB& cpBox, Index cp, const RigidBody& body, int part, Real dt, Real margin,
                SectionRule rule, BodyContact& out) {
  const OBB box = body.partBox(part);
  const BoxContact c = obbContact(cpBox, box, 0, 1, true);
  if (c.overlap) {
    out.normal = c.normal;
    out.gap = sectionGap(f, cp, box, c.normal, rule);
    out.point = meanPoint(c, cpBox.centre);
    out.s = alongCP(f, cp, out.point);
    out.time = 0;
    return true;
  }
  if (!(dt > 0)) return false;
  const Vec3 vb = body.velocityAt(box.centre);
  const Index i = f.elem0[cp];
  bool hit = false;
  for (Index k : {i, i + 1}) {  // either node's velocity brackets a CP that turns in the step
    const SweptContact sw = obbFirstContact(cpBox, f.vel[k], box, vb, dt);
    if (!sw.hit || (hit && sw.time >= out.time)) continue;
    hit = true;
    out.time = sw.time;
    out.normal = sw.contact.normal;
    // Back to the start of the step: the CP has not moved yet.
    out.point = meanPoint(sw.contact, cpBox.centre) - sw.time * f.vel[k];
    out.gap = std::max(Real(0), -(vb - f.vel[k]).dot(out.normal) * sw.time) + margin;
  }
  if (hit) out.s = alongCP(f, cp, out.point);
  return hit;
}

bool sphereContact(const Fabric& f, Index cp, const RigidBody& body, int part, Real dt, Real margin, SectionRule rule,
                   BodyContact& out) {
  const Vec3 c = body.partCentre(part);
  const Real R = body.parts[part].radius;
  const Index i = f.elem0[cp], j = i + 1;
  const Real s = alongCP(f, cp, c);
  const Vec3 axis = f.pos[j] - f.pos[i];
  const Vec3 q = f.pos[i] + s * axis;
  const Vec3 r = c - q;
  const Real dist = r.norm();
  const Vec3 t = axis.normalized();
  Vec3 d = (1 - s) * f.secDir[i] + s * (f.secDir[i].dot(f.secDir[j]) < 0 ? Vec3(-f.secDir[j]) : f.secDir[j]);
  d = (d - d.dot(t) * t).normalized();
  const Vec3 n = dist > 1e-12 * R ? Vec3(r / dist) : d;
  const SemiAxes si = semiAxes(f.secRadius[i], f.secFlat[i], rule), sj = semiAxes(f.secRadius[j], f.secFlat[j], rule);
  const Real support = ellipseSupport(t.cross(d), d, (1 - s) * si.a + s * sj.a, (1 - s) * si.b + s * sj.b, n);
  const Real gap = dist - R - support;
  const Vec3 point = q + (support + 0.5 * gap) * n;
  const Real vn = (body.velocityAt(point) - ((1 - s) * f.vel[i] + s * f.vel[j])).dot(n);  // < 0 approaching
  const Real reach = margin + (vn < 0 ? -vn * dt : 0.0);
  if (!(gap <= reach)) return false;
  out.normal = n;
  out.gap = gap;
  out.point = point;
  out.s = s;
  out.time = gap > margin ? (gap - margin) / -vn : 0.0;
  return true;
}
}  // namespace

bool cpBodyContact(const Fabric& f, const OBB& cpBox, Index cp, const RigidBody& body, int part, Real dt, Real margin,
                   SectionRule rule, BodyContact& out) {
  out.cp = cp, out.part = part;
  const RigidPart::Type type = body.parts[part].type;
  if (type == RigidPart::Type::Cylinder || type == RigidPart::Type::Triangle) return false;  // refused at add_body: gap model only
  return body.parts[part].type == RigidPart::Type::Box ? boxContact(f, cpBox, cp, body, part, dt, margin, rule, out)
                                                       : sphereContact(f, cp, body, part, dt, margin, rule, out);
}

}  // namespace woven
