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
#include "dynamics/Breakage.hpp"
#include "dynamics/Energy.hpp"
#include "dynamics/Loads.hpp"
#include "fabric/Fabric.hpp"

namespace woven {

/// Critical time step [s]: min over live elements of sqrt(m_e/K_e)*(sqrt(1+xi_e^2)-xi_e) with
/// m_e = rho*A*l0, i.e. l0*sqrt(rho/E)*(...): 2/omega_max of the central-difference scheme.
Real criticalTimeStep(const Fabric& f);

/// The elements stable at a step of outerDt [s] (1: slow, 0: fast), for multi-rate springs
/// (ChainDynamics::setSlowElements). Each node i bounds the frequencies its springs reach by
/// Gershgorin's theorem on M^-1 K: omega^2 <= 2 sum_e K_e / m_i over its live elements, so a step is
/// stable at the node up to dt_i = sqrt(2 m_i / sum_e K_e) (sqrt(1+xi^2)-xi), xi the largest damping
/// ratio there (for a uniform chain dt_i is criticalTimeStep exactly); an element is slow when
/// both its nodes have dt_i >= outerDt (a kinematic node: any step). Broken elements are fast.
std::vector<std::uint8_t> slowElements(const Fabric& f, Real outerDt);

struct InstabilityLimits {
  /// Stop if kinetic+elastic+damped+contact > factor*(|initial|+|work|+contact input)/(1-(dt/dt_crit)^2) + floor (the
  /// 1/(1-(dt/dt_crit)^2) is how far a stable step lets the energy of a linear chain oscillate above
  /// the scheme's invariant; it is 1 for dt >= dt_crit). The floor is the fabric's kinetic energy
  /// with every node at restSpeed: below it the books hold rounding, not motion (a fabric at rest
  /// under penalty contacts on the gap model reads ~1e-30 J, against 2.4e-22 J for the default ply's
  /// 0.47 g at 1 nm/s; a real blow-up grows past it within steps). restSpeed holds the place of the
  /// earlier absolute floor (1e-300 J) in the struct, so snapshots (engine/Snapshot) of earlier
  /// builds still read, with that old, nearly zero floor.
  Real blowupFactor = 3.0;
  Real restSpeed = 1e-9;          ///< [m/s]
  long checkpointInterval = 100;  ///< steps between copies of the last good state
};

/// What runs between the kick and the drift of a step (the collision stage): it sees x_n and the
/// velocities v_{n+1/2} that the drift will use, may change both, and returns the kinetic energy it
/// added [J] (negative when impulses dissipate).
class StepHook {
 public:
  virtual ~StepHook() = default;
  virtual Real beforeDrift(Fabric& f, Real dt) = 0;
  /// After the drift, on x_{n+1} and v_{n+1/2}, before the forces; returns the kinetic energy added [J].
  virtual Real afterDrift(Fabric& f, Real dt) { return 0; }
  /// Work the hook's rigid bodies did on the fabric in the calls since the last take [J]: part of
  /// the energy the calls returned that is not the contacts' dissipation (the books take it as work).
  virtual Real takeBodyWork() { return 0; }
  /// Spring energy the hook's position projection put in since the last take [J] (booked as
  /// EnergyBooks::projection, not as contact dissipation).
  virtual Real takeProjectionEnergy() { return 0; }
  /// Of the energy the calls since the last take took out, what friction took [J] (booked as
  /// EnergyBooks::friction instead of contact).
  virtual Real takeFrictionWork() { return 0; }
  /// Energy the hook's contact springs hold now, after beforeDrift [J] (EnergyBooks::spring); what
  /// they hold at its first call joins EnergyBooks::initial. Kept out of the energy beforeDrift returns, so that an unstable
  /// spring shows in the books' total (the blow-up check) instead of being booked away as contact input.
  virtual Real springEnergy() const { return 0; }
};

class ChainDynamics {
 public:
  explicit ChainDynamics(Fabric& fabric);

  InstabilityLimits limits;

  // --- loads (SI) ---
  /// Drives node i at velocity v [m/s] from now on (v = 0 fixes it).
  void prescribeVelocity(Index i, const Vec3& v);
  void fix(Index i) { prescribeVelocity(i, Vec3::Zero()); }
  /// Prescribed velocities reach their value linearly over `seconds` from time 0 (0: at once), so
  /// grips start without a shock wave.
  void setVelocityRamp(Real seconds);
  /// Makes a kinematic node free again.
  void release(Index i);
  /// Constant point force [N] on node i (zero removes it).
  void setPointForce(Index i, const Vec3& F);
  /// Turns breakage on or off (Breakage.hpp): validated first, then the yarn strengths are drawn and
  /// the strain filter starts from the current strains.
  void configureBreakage(const BreakageParams& p);
  const Breakage& breakage() const { return breakage_; }
  /// Body acceleration [m/s^2] on every free node (gravity).
  void setBodyAcceleration(const Vec3& g);
  const Loads& loads() const { return loads_; }
  bool isKinematic(Index i) const { return f_.invMass[i] == 0.0; }

  /// Advances one step of dt [s] > 0. Does not compare dt with the critical step (the engine does);
  /// throws InstabilityError on a non-finite state or an energy blow-up, before the bad values
  /// reach the state where it can, and keeps the last good state in any case.
  /// With a hook, the kick and the drift run as two passes with hook->beforeDrift between them.
  /// outerEnd: the step ends a step of the slow elements (setSlowElements; always true without them).
  void step(Real dt, StepHook* hook = nullptr, bool outerEnd = true);
  /// Multi-rate springs, the impulse form of r-RESPA (Tuckerman, Berne & Martyna 1992) over the
  /// elements: the `slow` ones (slowElements) act as the slow force, a kick of m dt / 2 at each end
  /// of a step of m chain steps, the others at every chain step. Fused with the leapfrog's kicks this
  /// is one rule: the force a chain step leaves is the fast elements' plus, where the step ends a
  /// slow step, m times the slow ones' (so the next kick of dt/2 gives them m dt/2), else nothing of
  /// them; the synchronised velocity there is then r-RESPA's, and the books close at slow steps'
  /// ends (in between, the kinetic book lacks the slow half kick still owed). A slow element's
  /// dashpot dissipates over m dt, its elastic energy is booked at every chain step.
  /// Empty or m = 1: one rate, the same bits as before. m is also the engine's substeps with one
  /// rate: the last good state is kept only at a step's end. Call at a slow step's end. A change of
  /// the split after the first step re-splits the kick the last step still owes (see the .cpp):
  /// exact, the synchronised velocities and the books stay.
  void setSlowElements(std::vector<std::uint8_t> slow, int m);
  const std::vector<std::uint8_t>& slowElementMask() const { return slow_; }
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
  /// dt of the last step [s] (0 before the first): the half-kick the next step owes the velocities.
  Real lastDt() const { return dtPrev_; }
  /// Sets the clock (step count, time [s], last dt [s]) of a loaded state, so the run continues
  /// exactly as the saved one would have.
  void setClock(long step, Real time, Real lastDt);
  /// The books as the step left them (kinetic of the last integer step; energy() synchronises it).
  const EnergyBooks& books() const { return books_; }
  bool booksStarted() const { return started_; }
  bool springSeen() const { return springSeen_; }
  /// Puts back what a state file carries beyond positions, velocities and sections (call after the
  /// fabric holds them; the caller has checked everything): clock, energy books, breakage state. The
  /// forces are recomputed without touching the books, and the loaded state becomes the last good one.
  void restore(long step, Real time, Real lastDt, const EnergyBooks& books, bool booksStarted, bool springSeen,
               const BreakageState& breakage);
  /// A hand edit of the state (a node's velocity or position set from outside) changed the energy by
  /// `delta` [J]: it joins the initial energy, so the blow-up check and the balance start from the
  /// edited state (else a push from rest looks like a blow-up at the next step).
  void bookEdit(Real delta) {
    if (started_ && std::isfinite(delta)) books_.initial += delta;
  }
  /// Velocity of node i at the current integer step, v_n = v_{n-1/2} + dt/2 a_n [m/s].
  Vec3 syncVelocity(Index i) const;
  /// Total reaction force [N] of the supports on the kinematic nodes in `nodes`.
  Vec3 reaction(const std::vector<Index>& nodes) const;

  const Vec3Array& lastGoodPos() const { return goodPos_; }
  const Vec3Array& lastGoodVel() const { return goodVel_; }
  const std::vector<Real>& lastGoodFlat() const { return goodFlat_; }
  const std::vector<std::uint8_t>& lastGoodAlive() const { return goodAlive_; }
  const std::vector<Real>& lastGoodStiffness() const { return goodStiffness_; }
  const std::vector<Real>& lastGoodDamping() const { return goodDamping_; }
  const EnergyBooks& lastGoodBooks() const { return goodBooks_; }
  bool lastGoodSpringSeen() const { return goodSpringSeen_; }
  const BreakageState& lastGoodBreakage() const { return goodBreak_; }
  const Vec3Array& lastGoodDir() const { return goodDir_; }
  long lastGoodStep() const { return goodStep_; }
  Real lastGoodDt() const { return goodDtPrev_; }
  Real lastGoodTime() const { return goodTime_; }
  /// Puts the last good state back into the fabric (positions, velocities, sections, broken
  /// elements, step, time).
  void restoreLastGood();

 private:
  template <bool Gravity, bool Drift>
  Real kickDrift(Real dt, Vec3& momentum);
  template <bool Gravity>
  void drift(Real dt, Vec3& momentum);
  template <bool StoreElementState>
  void springForces(Real dt);  // slow elements weighted by slowNow_
  Real bendingForces();         // adds the yarns' bending forces; returns their energy [J]
  void finishLoads(Real dt);
  void computeForces(Real dt);  // springForces + finishLoads: forces at the current state
  void start();
  void checkpoint();
  Vec3 acceleration(Index i) const;
  [[noreturn]] void failNonFinite();
  void bookContact(Real added);  // energy a StepHook added [J]

  Fabric& f_;
  Loads loads_;
  bool springSeen_ = false;  // the hook's spring energy at its first step went into books_.initial
  EnergyBooks books_;   // kinetic of the previous integer step, elastic/damped/work of the current
  long step_ = 0;
  Real time_ = 0;
  Real dtPrev_ = 0;
  Real dtCrit_ = 0;     // criticalTimeStep of the fabric: the engine's dt limit and the blow-up budget
  bool bendingOn_ = false;  // some yarn has a bending stiffness (bendingForces; set at construction)
  Real mass_ = 0;       // the fabric's mass [kg] (the blow-up floor)
  Breakage breakage_;
  std::vector<std::uint8_t> slow_;  // per element: 1 slow (multi-rate), empty: one rate
  int rate_ = 1;                    // chain steps per slow step (1: one rate)
  int chainSteps_ = 1;              // chain steps per engine step (substeps), multi-rate or not
  Real slowNow_ = 1;                // weight of the slow elements' forces the next springForces leaves
  Vec3Array edge_;     // springForces: force of each chunk's first CP on the node the chunk before assigns
  Vec3Array goodPos_, goodVel_, goodDir_;
  std::vector<Real> goodFlat_, goodStiffness_, goodDamping_;
  std::vector<std::uint8_t> goodAlive_;
  long goodStep_ = 0;
  Real goodTime_ = 0, goodDtPrev_ = 0;
  EnergyBooks goodBooks_;
  bool goodSpringSeen_ = false;
  BreakageState goodBreak_;
  bool started_ = false;
};

}  // namespace woven
