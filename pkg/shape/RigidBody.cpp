#include "shape/RigidBody.hpp"
#include "core/Errors.hpp"
#include "shape/Cylinder.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

// Physical ranges, not only finiteness: a velocity of 1e300 m/s or an infinite inertia passed a
// finiteness or sign check and turned into NaN at the first impulse (README, Parameters).
void RigidBody::validate() const {
  require(!parts.empty(), "parts", 0, "at least one Box, Sphere, Cylinder or Triangle part");
  const auto unit = [](const Quat& q) { return q.coeffs().allFinite() && std::abs(q.norm() - 1) < 1e-6; };
  for (const RigidPart& p : parts) {
    if (p.type == RigidPart::Type::Box)
      require(p.halfSize.allFinite() && p.halfSize.minCoeff() >= 1e-9 && p.halfSize.maxCoeff() <= 10, "extents",
              p.halfSize.allFinite() ? p.halfSize.minCoeff() : NAN, "[1e-9, 10] m on every axis");
    else if (p.type == RigidPart::Type::Triangle) {
      bool finite = true;
      Real far = 0;
      for (const Vec3& v : p.vert) finite = finite && v.allFinite(), far = std::max(far, v.norm());
      require(finite && far <= 10, "triangle", finite ? far : NAN, "corners finite, within 10 m of the part centre");
      const Real area = 0.5 * (p.vert[1] - p.vert[0]).cross(p.vert[2] - p.vert[0]).norm();
      require(area >= 1e-18, "triangle", area, "an area >= 1e-18 m^2 (three corners not on one line)");
    } else
      require(std::isfinite(p.radius) && p.radius >= 1e-9 && p.radius <= 10, "radius", p.radius, "[1e-9, 10] m");
    if (p.type == RigidPart::Type::Cylinder) validateCylinder(p);
    require(p.offset.allFinite() && p.offset.norm() <= 10, "offset", p.offset.norm(), "finite, |offset| <= 10 m");
    require(unit(p.ori), "part orientation", p.ori.norm(), "a finite unit quaternion (|q| = 1 within 1e-6)");
  }
  require(friction < 0 || (std::isfinite(friction) && friction <= 2), "body friction", friction,
          "[0, 2], or negative for the law's body_friction");
  require(!std::isnan(mass) && mass >= 0 && (mass <= 1e6 || std::isinf(mass)), "mass", mass,
          "[0, 1e6] kg, or inf (0 or inf: kinematic body)");
  if (dynamic())
    require(inertia.allFinite() && (inertia.array() >= 0).all() && inertia.maxCoeff() <= 1e6, "inertia",
            inertia.allFinite() ? inertia.maxCoeff() : NAN, "[0, 1e6] kg m^2 on each principal axis (finite)");
  else
    require(!inertia.hasNaN() && (inertia.array() >= 0).all(), "inertia", inertia.minCoeff(), "[0, inf] kg m^2");
  require(pos.allFinite() && pos.cwiseAbs().maxCoeff() <= 1e3, "pos", pos.allFinite() ? pos.cwiseAbs().maxCoeff() : NAN,
          "finite coordinates within [-1e3, 1e3] m");
  require(vel.allFinite() && vel.norm() <= 1e5, "velocity", vel.norm(), "finite, |v| <= 1e5 m/s");
  require(angVel.allFinite() && angVel.norm() <= 1e7, "angular_velocity", angVel.norm(), "finite, |w| <= 1e7 rad/s");
  require(unit(ori), "orientation", ori.norm(), "a finite unit quaternion (|q| = 1 within 1e-6)");
}

}  // namespace woven
