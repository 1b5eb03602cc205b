#include "law/NormalForces.hpp"
#include "core/Errors.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

Real penaltyDtLimit(Real m, Real k) {
  require(std::isfinite(m) && m > 0, "m", m, "(0, inf) kg");
  require(std::isfinite(k) && k > 0, "k", k, "(0, inf) N/m");
  return 2 * std::sqrt(m / k);
}

void NormalForces::addYarn(const Fabric& f, const CPContact& c, Real spring, Real k, Real zeta) {
  Row r;
  r.node[0] = f.elem0[c.cpA], r.node[1] = r.node[0] + 1, r.node[2] = f.elem0[c.cpB], r.node[3] = r.node[2] + 1;
  r.w[0] = -(1 - c.sA), r.w[1] = -c.sA, r.w[2] = 1 - c.sB, r.w[3] = c.sB;
  r.n = c.normal, r.spring = spring;
  Real K = 0;
  for (int q = 0; q < 4; ++q) K += r.w[q] * r.w[q] * f.invMass[r.node[q]];
  r.mEff = K > 0 ? 1 / K : 0;
  r.damper = 2 * zeta * std::sqrt(k * r.mEff);
  rows_.push_back(r);
}

void NormalForces::addBody(const Fabric& f, const BodyContact& c, const std::vector<RigidBody>& bodies, Real spring,
                           Real k, Real zeta) {
  Row r;
  r.node[0] = f.elem0[c.cp], r.node[1] = r.node[0] + 1, r.node[2] = r.node[3] = r.node[0];
  r.w[0] = -(1 - c.s), r.w[1] = -c.s, r.w[2] = r.w[3] = 0;
  r.n = c.normal, r.spring = spring, r.body = c.body;
  const RigidBody& b = bodies[c.body];
  r.arm = c.point - b.pos;
  const Vec3 rn = r.arm.cross(r.n);
  Real K = b.invMass() + rn.dot(b.invInertiaWorld() * rn);
  for (int q = 0; q < 2; ++q) K += r.w[q] * r.w[q] * f.invMass[r.node[q]];
  r.mEff = K > 0 ? 1 / K : 0;
  r.damper = 2 * zeta * std::sqrt(k * r.mEff);
  rows_.push_back(r);
}

Real NormalForces::normalVelocity(const Fabric& f, const std::vector<RigidBody>* bodies, const Row& r) const {
  Vec3 v = Vec3::Zero();
  for (int q = 0; q < 4; ++q) v += r.w[q] * f.vel[r.node[q]];
  if (r.body >= 0) {
    const RigidBody& b = (*bodies)[r.body];
    v += b.vel + b.angVel.cross(r.arm);
  }
  return v.dot(r.n);
}

void NormalForces::apply(Fabric& f, std::vector<RigidBody>* bodies, Real dt, NormalForceReport& rep) {
  rep = NormalForceReport{};
  force_.assign(rows_.size(), 0);
  vn0_.assign(rows_.size(), 0);
  Real ke0 = 0;
  if (bodies)
    for (const RigidBody& b : *bodies) ke0 += b.dynamic() ? b.kineticEnergy() : 0;
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    const Row& r = rows_[k];
    if (!(r.mEff > 0)) continue;  // both sides kinematic
    vn0_[k] = normalVelocity(f, bodies, r);
    force_[k] = std::max(Real(0), r.spring - r.damper * vn0_[k]);
    rep.rows += force_[k] > 0;
  }
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    if (force_[k] == 0) continue;
    const Row& r = rows_[k];
    const Vec3 J = (force_[k] * dt) * r.n;  // on B; -J on A
    for (int q = 0; q < 4; ++q) f.vel[r.node[q]] += (r.w[q] * f.invMass[r.node[q]]) * J;
    if (r.body >= 0) {
      RigidBody& b = (*bodies)[r.body];
      if (!b.dynamic()) {  // a kinematic body gives the fabric -J times its own velocity at the point
        rep.bodyWork += -J.dot(b.vel + b.angVel.cross(r.arm));
        continue;
      }
      b.vel += b.invMass() * J;
      b.angVel += b.invInertiaWorld() * r.arm.cross(J);
    }
  }
  // Dashpot work: the force beyond the spring, against the mean normal speed over the kick; and
  // the springs' energy change over the first half of the drift (header).
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    if (!(rows_[k].mEff > 0)) continue;
    const Real vn1 = normalVelocity(f, bodies, rows_[k]);
    rep.halfDrift -= 0.5 * dt * rows_[k].spring * vn1;
    if (force_[k] > 0) rep.dissipated += -(force_[k] - rows_[k].spring) * 0.5 * (vn0_[k] + vn1) * dt;
  }
  if (bodies)
    for (const RigidBody& b : *bodies) rep.bodyWork += b.dynamic() ? -b.kineticEnergy() : 0;
  if (bodies) rep.bodyWork += ke0;
}

}  // namespace woven
