#include "shape/RigidBody.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

void RigidBody::validate() const {
  require(!parts.empty(), "parts", 0, "at least one Box or Sphere part");
  for (const RigidPart& p : parts) {
    if (p.type == RigidPart::Type::Box)
      require(p.halfSize.allFinite() && (p.halfSize.array() > 0).all(), "extents", p.halfSize.minCoeff(),
              "(0, inf) m on every axis");
    else
      require(std::isfinite(p.radius) && p.radius > 0, "radius", p.radius, "(0, inf) m");
    require(p.offset.allFinite(), "offset", p.offset.norm(), "finite [m]");
  }
  require(!std::isnan(mass) && mass >= 0, "mass", mass, "(0, inf] kg (0 or inf: kinematic body)");
  require(!inertia.hasNaN() && (inertia.array() >= 0).all(), "inertia", inertia.minCoeff(), "[0, inf] kg m^2");
  require(pos.allFinite(), "pos", pos.norm(), "finite [m]");
  require(vel.allFinite(), "velocity", vel.norm(), "finite [m/s]");
  require(angVel.allFinite(), "angular_velocity", angVel.norm(), "finite [rad/s]");
  require(std::isfinite(ori.norm()) && std::abs(ori.norm() - 1) < 1e-6, "orientation", ori.norm(), "a unit quaternion");
}

}  // namespace woven
