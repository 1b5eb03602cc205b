#include "shape/Cylinder.hpp"
#include "core/Errors.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

void validateCylinder(const RigidPart& p) {
  require(std::isfinite(p.halfLength) && p.halfLength >= 1e-9 && p.halfLength <= 10, "half_length", p.halfLength,
          "[1e-9, 10] m");
  require(std::isfinite(p.chiselAngle) && p.chiselAngle >= 0 && p.chiselAngle < 0.5 * M_PI, "chisel_angle",
          p.chiselAngle, "[0, pi/2) rad (0: no chisel)");
  if (p.chiselAngle > 0) {
    require(std::isfinite(p.landHalfWidth) && p.landHalfWidth >= 0 && p.landHalfWidth < p.radius, "land_half_width",
            p.landHalfWidth, "[0, radius) m");
    const Real noseLength = (p.radius - p.landHalfWidth) / std::tan(p.chiselAngle);
    require(noseLength < 2 * p.halfLength, "chisel_angle", p.chiselAngle,
            "an angle whose flats end before the tail: (radius - land) / tan(angle) < length");
  }
}

Real cylinderMinAlong(const RigidPart& p, const Vec3& n) {
  const Real R = p.radius, H = p.halfLength, nr = std::hypot(n.x(), n.y());
  if (!(p.chiselAngle > 0)) return -H * std::abs(n.z()) - R * nr;  // the round cylinder's support
  const Real w = p.landHalfWidth, cot = 1 / std::tan(p.chiselAngle);
  Real best = INFINITY;
  const auto at = [&](Real x, Real y, Real z) { best = std::min(best, x * n.x() + y * n.y() + z * n.z()); };
  // Tail rim (z = -H, whole: the flats end before it): its lowest point along n.
  if (nr > 0) at(-R * n.x() / nr, -R * n.y() / nr, -H);
  else at(R, 0, -H);
  // The land's corners, and the nose rim's arcs (|x| <= w on z = H).
  const Real yc = std::sqrt(R * R - w * w);
  for (Real sx : {-1.0, 1.0})
    for (Real sy : {-1.0, 1.0}) at(sx * w, sy * yc, H);
  if (nr > 0 && std::abs(R * n.x() / nr) <= w) at(-R * n.x() / nr, -R * n.y() / nr, H);
  // The flats' arcs on the round surface: x = R cos(th) (>= w on the + flat, <= -w on the - flat),
  // y = R sin(th), z = H - (|x| - w) cot(alpha); along it y.n = R cos(th) (nx -+ nz cot) + R sin(th) ny
  // + const, lowest at (cos, sin) along -(nx -+ nz cot, ny) when that lies on the arc (else at its
  // ends, the land's corners).
  for (Real sx : {-1.0, 1.0}) {
    const Real ax = n.x() - sx * n.z() * cot, ay = n.y(), m = std::hypot(ax, ay);
    if (!(m > 0)) continue;
    const Real x = -R * ax / m, y = -R * ay / m;
    if (sx * x >= w) at(x, y, H - (sx * x - w) * cot);
  }
  return best;
}

int cylinderDirections(const RigidPart& p, const Vec3& q, Vec3 out[6]) {
  int k = 0;
  out[k++] = -Vec3::UnitZ();  // the nose face's outward normal is +z: the plane's normal towards the part is -z
  out[k++] = Vec3::UnitZ();   // the tail face
  const Real qr = std::hypot(q.x(), q.y());
  const Vec3 radial = qr > 0 ? Vec3(q.x() / qr, q.y() / qr, 0) : Vec3::UnitX();
  out[k++] = -radial;
  // The closest point of the round cylinder: exact direction for a point beyond a rim.
  const Real H = p.halfLength;
  const Vec3 c = Vec3(0, 0, std::clamp(q.z(), -H, H)) + std::min(qr, p.radius) * radial;
  const Vec3 d = c - q;
  if (d.norm() > 1e-15) out[k++] = d.normalized();
  if (p.chiselAngle > 0) {
    const Real ca = std::cos(p.chiselAngle), sa = std::sin(p.chiselAngle);
    out[k++] = -Vec3(ca, 0, sa);  // the + flat's outward normal is (cos, 0, sin)
    out[k++] = -Vec3(-ca, 0, sa);
  }
  return k;
}

}  // namespace woven
