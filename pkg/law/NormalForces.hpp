// Force-based contact response (the alternatives to the impulses of law/ImpulseLaw; docs/collisions.md,
// "Response and section models"): a normal force F >= 0 on each listed contact, applied for the
// step's dt as a velocity change of v_{n+1/2}, with the weights of an impulse row (Eq. 4): node k of
// the contact gets dv_k = w_k F dt n / m_k, w = -(1-sA), -sA on A and (1-sB), sB on B, so the
// momentum changes of the four nodes sum to zero exactly. A row whose B side is a rigid body
// (geom/BodyContact) gives the body +F dt n at the contact point (its velocity and, through the
// arm, its angular velocity), the CP -F dt n.
// Each row carries a spring force F_s (penalty k_p delta, or the section springs of Eq. 7) and a
// dashpot c = 2 zeta sqrt(k m_eff) on the normal approach speed, F = max(0, F_s - c vn), with
// 1/m_eff = sum w_k^2 / m_k (+ 1/M + (r x n).I^-1(r x n) for a body). All forces are taken from the
// velocities before any is applied (a force evaluation, as in the element springs: order-free).
// The spring energy belongs to the caller (it knows the springs); the dashpot's dissipation, the
// rigid bodies' work and the half-kick term below are reported here for the energy books.
// Energy: the chain's energy books pair the kinetic energy of the synchronised velocities at x_{n+1}
// (v_{n+1/2} + dt/2 a_{n+1}, which cannot hold these forces' half kick at x_{n+1}: it is not known
// yet) with the spring energy half way through the drift, U(x_{n+1/2}) = U(x_n) - F_s vn dt/2 to
// first order (vn the rows' normal speed after the kick): the leapfrog pair that is conserved to
// O(dt^2). That drift term is reported (halfDrift) for the spring book.
// Stability: a contact is a mass-spring pair m_eff, k: stable for dt <= 2 sqrt(m_eff / k)
// (penaltyDtLimit). Nothing guards against a larger dt here: the instability is shown, not hidden.
#pragma once
#include "fabric/Fabric.hpp"
#include "geom/BodyContact.hpp"
#include "geom/CPContact.hpp"
#include "shape/RigidBody.hpp"
#include <vector>

namespace woven {

/// Largest stable time step [s] of a penalty contact of effective mass m [kg] and stiffness k [N/m]:
/// 2 sqrt(m / k) (central difference on an undamped spring).
Real penaltyDtLimit(Real m, Real k);

struct NormalForceReport {
  long rows = 0;          ///< contacts that received a force
  Real dissipated = 0;    ///< work of the dashpots taken out of the motion in the step [J] (>= 0 up to O(dt^2))
  Real bodyWork = 0;      ///< work the rigid bodies did on the fabric [J] (as ImpulseReport::bodyWork)
  Real halfDrift = 0;     ///< change of the spring energy over the first half of the drift, -sum F_s vn dt/2 [J]
};

class NormalForces {
 public:
  void clear() { rows_.clear(); }
  /// Adds a CP-CP contact with spring force `spring` [N] >= 0 of stiffness k [N/m] and a dashpot of
  /// damping ratio zeta in [0, 1).
  void addYarn(const Fabric& f, const CPContact& c, Real spring, Real k, Real zeta);
  /// Adds a CP-body contact (body c.body of `bodies`).
  void addBody(const Fabric& f, const BodyContact& c, const std::vector<RigidBody>& bodies, Real spring, Real k,
               Real zeta);
  /// Effective mass m_eff [kg] of the contacts added, in order (0: both sides kinematic).
  Real effectiveMass(std::size_t row) const { return rows_[row].mEff; }
  std::size_t size() const { return rows_.size(); }
  /// Force [N] of row k in the last apply().
  Real force(std::size_t k) const { return force_[k]; }
  /// Applies the forces for dt [s] to Fabric::vel and the bodies.
  void apply(Fabric& f, std::vector<RigidBody>* bodies, Real dt, NormalForceReport& report);

 private:
  struct Row {
    Index node[4];
    Real w[4];
    Vec3 n;
    Real spring, damper, mEff;  // [N], c [N s/m], [kg]
    int body = -1;
    Vec3 arm = Vec3::Zero();
  };
  Real normalVelocity(const Fabric& f, const std::vector<RigidBody>* bodies, const Row& r) const;
  std::vector<Row> rows_;
  std::vector<Real> force_, vn0_;

};

}  // namespace woven
