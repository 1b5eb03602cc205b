#include "collider/BodyCollider.hpp"
#include <algorithm>

namespace woven {

void BodyCollider::collide(const Fabric& f, const std::vector<OBB>& grown, const std::vector<Real>& grow,
                           const std::vector<RigidBody>& bodies, Real dt, std::vector<BodyCandidate>& out) {
  Real fabricStep = 0, bodyStep = 0;
  for (Real g : grow) fabricStep = std::max(fabricStep, g);
  std::size_t layout = 0;
  for (const RigidBody& b : bodies) {
    layout = layout * 31 + b.parts.size() + 1;
    Real reach = 0;  // farthest a part's point goes in the step
    for (std::size_t k = 0; k < b.parts.size(); ++k)
      reach = std::max(reach, b.angVel.norm() * ((b.partCentre(k) - b.pos).norm() + aabbHalf(b.partBox(k)).norm()));
    bodyStep = std::max(bodyStep, dt * (b.vel.norm() + reach));
  }
  travelled_ += fabricStep + bodyStep;
  if (!(valid_ && layout == layout_ && travelled_ <= skin)) {
    list_.clear();
    for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
      const RigidBody& b = bodies[bi];
      for (std::size_t k = 0; k < b.parts.size(); ++k) {
        const OBB box = b.partBox(k);
        const Vec3 lo = box.centre - aabbHalf(box) - Vec3::Constant(skin + bodyStep);
        const Vec3 hi = box.centre + aabbHalf(box) + Vec3::Constant(skin + bodyStep);
        for (Index e = 0; e < f.nElems(); ++e) {
          if (!f.alive[e]) continue;
          const Vec3 h = aabbHalf(grown[e]);
          if (((grown[e].centre + h).array() >= lo.array()).all() && ((grown[e].centre - h).array() <= hi.array()).all())
            list_.push_back({e, static_cast<int>(bi), static_cast<int>(k)});
        }
      }
    }
    travelled_ = 0;
    valid_ = true;
    layout_ = layout;
    ++rebuilds;
  }
  out.clear();
  for (const BodyCandidate& c : list_)
    if (f.alive[c.cp]) out.push_back(c);
}

}  // namespace woven
