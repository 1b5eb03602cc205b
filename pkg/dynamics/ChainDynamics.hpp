// Yarn-chain dynamics: axial springs with dashpots (paper Eq. 3), loads, and the explicit
// velocity-Verlet integrator, with the two half-kicks of consecutive steps fused (leapfrog), so each
// step is one pass over the nodes and one over the CPs.
//
// One step (n -> n+1), state x_n, v_{n-1/2}, f_n:
//   nodes:    v_n = v_{n-1/2} + dt_prev/2 a_n          (kinetic energy of step n)
//             v_{n+1/2} = v_n + dt/2 a_n ;  x_{n+1} = x_n + dt v_{n+1/2}
//   elements: f_{n+1} = springs(x_{n+1}) + dashpots(v_{n+1/2}) + point forces
// Stable for dt <= dt_crit = min_e l0*sqrt(rho/E)*(sqrt(1+xi^2) - xi)  (physics-reference.md).
#pragma once
#include "core/Types.hpp"
#include "dynamics/Energy.hpp"
#include "dynamics/Loads.hpp"
#include "fabric/Fabric.hpp"

namespace woven {

/// Critical time step [s]: min over live elements of sqrt(m_e/K_e)*(sqrt(1+xi_e^2)-xi_e) with
/// m_e = rho*A*l0, i.e. l0*sqrt(rho/E)*(...): 2/omega_max of the central-difference scheme.
Real criticalTimeStep(const Fabric& f);

struct InstabilityLimits {
  /// Stop if kinetic+elastic+damped > factor*(initial+|work|)/(1-(dt/dt_crit)^2) + floor (the
  /// 1/(1-(dt/dt_crit)^2) is how far a stable step lets the energy of a linear chain oscillate above
  /// the scheme's invariant; it is 1 for dt >= dt_crit).
  Real blowupFactor = 3.0;
  Real energyFloor = 1e-300;      ///< [J]
  long checkpointInterval = 100;  ///< steps between copies of the last good state
};

class ChainDynamics {
 public:
  explicit ChainDynamics(Fabric& fabric);

  InstabilityLimits limits;

  // --- loads (SI) ---
  /// Drives node i at velocity v [m/s] from now on (v = 0 fixes it).
  void prescribeVelocity(Index i, const Vec3& v);
  void fix(Index i) { prescribeVelocity(i, Vec3::Zero()); }
  /// Makes a kinematic node free again.
  void release(Index i);
  /// Constant point force [N] on node i (zero removes it).
  void setPointForce(Index i, const Vec3& F);
  /// Body acceleration [m/s^2] on every free node (gravity).
  void setBodyAcceleration(const Vec3& g);
  const Loads& loads() const { return loads_; }
  bool isKinematic(Index i) const { return f_.invMass[i] == 0.0; }

  /// Advances one step of dt [s] > 0. Does not compare dt with the critical step (the engine does);
  /// throws InstabilityError on a non-finite state or an energy blow-up, before the bad values
  /// reach the state where it can, and keeps the last good state in any case.
  void step(Real dt);
  /// Recomputes forces at the current state, and the CPs' strain and tension (Fabric::strain,
  /// Fabric::tension), which step() leaves as they were: call it before reading them, and after
  /// moving nodes by hand.
  void refreshForces();

  /// Energy books at the current state (computes the synchronised kinetic energy: O(nodes)).
  EnergyBooks energy() const;
  long stepCount() const { return step_; }
  /// Critical time step [s] of the fabric (criticalTimeStep), computed at construction.
  Real criticalDt() const { return dtCrit_; }
  Real time() const { return time_; }  ///< [s]
  /// Velocity of node i at the current integer step, v_n = v_{n-1/2} + dt/2 a_n [m/s].
  Vec3 syncVelocity(Index i) const;
  /// Total reaction force [N] of the supports on the kinematic nodes in `nodes`.
  Vec3 reaction(const std::vector<Index>& nodes) const;

  const Vec3Array& lastGoodPos() const { return goodPos_; }
  const Vec3Array& lastGoodVel() const { return goodVel_; }
  long lastGoodStep() const { return goodStep_; }
  Real lastGoodTime() const { return goodTime_; }
  /// Puts the last good state back into the fabric (positions, velocities, step, time).
  void restoreLastGood();

 private:
  template <bool Gravity>
  Real kickDrift(Real dt, Vec3& momentum);
  template <bool StoreElementState>
  void springForces(Real dt);
  void finishLoads(Real dt);
  void computeForces(Real dt);  // springForces + finishLoads: forces at the current state
  void start();
  void checkpoint();
  Vec3 acceleration(Index i) const;
  [[noreturn]] void failNonFinite();

  Fabric& f_;
  Loads loads_;
  EnergyBooks books_;   // kinetic of the previous integer step, elastic/damped/work of the current
  long step_ = 0;
  Real time_ = 0;
  Real dtPrev_ = 0;
  Real dtCrit_ = 0;     // criticalTimeStep of the fabric: the engine's dt limit and the blow-up budget
  Vec3Array goodPos_, goodVel_;
  long goodStep_ = 0;
  Real goodTime_ = 0;
  bool started_ = false;
};

}  // namespace woven
