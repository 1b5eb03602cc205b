// FabricEngine: one step of the whole fabric, top to bottom (docs/design.md): kick, collisions
// (refit, broad phase, narrow phase, response: CollisionStage) when enabled, drift, springs.
// Owns the fabric; the YADE adapter (py/woven/engine.py) calls step(O.dt) once per YADE iteration.
#pragma once
#include "core/Types.hpp"
#include "dynamics/ChainDynamics.hpp"
#include "engine/CollisionStage.hpp"
#include "fabric/Fabric.hpp"
#include "fabric/StateIO.hpp"
#include <memory>
#include <string>

namespace woven {

class FabricEngine {
 public:
  explicit FabricEngine(Fabric fabric);
  FabricEngine(const FabricEngine&) = delete;
  FabricEngine& operator=(const FabricEngine&) = delete;

  Fabric& fabric() { return *fabric_; }
  const Fabric& fabric() const { return *fabric_; }
  ChainDynamics& dynamics() { return dynamics_; }
  const ChainDynamics& dynamics() const { return dynamics_; }

  /// Critical time step of the chain [s] (see criticalTimeStep).
  Real criticalDt() const { return dynamics_.criticalDt(); }
  /// The longest step() accepts [s]: substeps() x criticalDt().
  Real maxStep() const { return substeps_ * criticalDt(); }
  /// Advances one step of dt [s]: substeps() chain steps of dt / substeps(), the collision pass once,
  /// before the first. Refuses (ParameterError "dt") any dt outside (0, maxStep()].
  void step(Real dt);
  /// Spring substeps per step (multiple time stepping: the impulse form of r-RESPA, Tuckerman, Berne
  /// & Martyna, J. Chem. Phys. 97, 1990 (1992); Grubmueller et al.'s Verlet-I, Mol. Sim. 6, 121
  /// (1991)). The yarns' springs, the cheap fast part, step at dt / m, within their own stable step;
  /// the collision stage, the costly slow part, runs once per step of dt: its impulses act as a kick
  /// at the step's start, its rows share each contact's room over the whole step (its horizon) and
  /// its projection runs after the last substep. So a fabric whose finest CPs set dt_crit (adaptive
  /// resolution: m = cp_per_span / cp_coarse) meets its contacts at the rate of its coarse CPs.
  /// m in [1, 64] (ParameterError "substeps"); above 1 only with an impulse-only collision stage (no
  /// penalty response, no section springs: their forces would act over one substep).
  void setSubsteps(int m);
  int substeps() const { return substeps_; }
  /// Multi-rate springs with substeps m > 1 (off: every spring steps at dt / m). The elements stable
  /// at the longest step accepted, m x dt_crit (slowElements: the coarse CPs of an adaptive fabric),
  /// step once per dt as r-RESPA's slow force (ChainDynamics::setSlowElements), the others m times.
  /// Between two passes the nodes of slow elements alone then move at constant velocity but for
  /// impulses, so a later substep solves again only the rows near a fast node or a body
  /// (CollisionStage::setSlowNodes); the rest were solved for the whole step by the pass.
  void setMultiRate(bool on);
  bool multiRate() const { return multiRate_; }

  /// Turns collision handling on with these parameters (validated first; nothing changes on bad
  /// input), or updates them.
  void enableCollisions(const ContactParams& p, BroadPhase broad = BroadPhase::YarnTree);
  void disableCollisions() { collisions_.reset(); }
  /// The collision stage, or nullptr when collisions are off.
  CollisionStage* collisions() { return collisions_.get(); }
  const CollisionStage* collisions() const { return collisions_.get(); }

  KinematicState state() const;
  /// Writes the state to `path` (StateIO), the collision stage's memory with it: a pure
  /// observation, and a run loaded from the file continues bit for bit as this one does.
  void saveState(const std::string& path);
  KinematicState lastGoodState() const;
  /// Loads a saved state (same node count), bit for bit: positions, velocities, sections, the clock
  /// and the collision stage's memory, so the run goes on exactly as the saved one does.
  /// Everything is checked before anything changes (checkState): a refused state leaves the engine
  /// as it was. The energy books, broken elements and breakage state come from the state too.
  void setState(const KinematicState& s);
  /// Throws ParameterError ("state", "step", "time", "last_dt") unless s is a valid state of this
  /// engine's fabric: sizes, topology fingerprint, clock, finite values, sections, elements, breakage.
  void checkState(const KinematicState& s) const;

 private:
  std::unique_ptr<Fabric> fabric_;  // heap-held so the dynamics' reference stays valid
  ChainDynamics dynamics_;
  std::unique_ptr<CollisionStage> collisions_;
  int substeps_ = 1;
  bool multiRate_ = false;
  // The slow elements of (substeps_, multiRate_) and their nodes, to the dynamics and the stage.
  void applyRates();
};

}  // namespace woven
