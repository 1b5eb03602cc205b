// FabricEngine: one step of the whole fabric, top to bottom (docs/design.md). This step is
// the chain dynamics; collisions (refit, broad phase, narrow phase, response) slot in before it.
// Owns the fabric; the YADE adapter (py/woven/engine.py) calls step(O.dt) once per YADE iteration.
#pragma once
#include "core/Types.hpp"
#include "dynamics/ChainDynamics.hpp"
#include "fabric/Fabric.hpp"
#include "fabric/StateIO.hpp"
#include <memory>

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
  /// Advances one step of dt [s]. Refuses (ParameterError "dt") any dt outside (0, dt_crit].
  void step(Real dt);

  KinematicState state() const;
  KinematicState lastGoodState() const;
  /// Loads a saved state (same node count), bit for bit.
  void setState(const KinematicState& s);

 private:
  std::unique_ptr<Fabric> fabric_;  // heap-held so the dynamics' reference stays valid
  ChainDynamics dynamics_;
};

}  // namespace woven
