#include "engine/FabricEngine.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

FabricEngine::FabricEngine(Fabric fabric)
    : fabric_(std::make_unique<Fabric>(std::move(fabric))), dynamics_(*fabric_) {}

void FabricEngine::step(Real dt) {
  const Real dtCrit = dynamics_.criticalDt();
  // Refused before anything moves: a step above the central-difference limit grows without bound.
  if (!(std::isfinite(dt) && dt > 0 && dt <= dtCrit * (1 + 1e-12)))  // message built only on failure
    throw ParameterError("dt", fmt(dt), "(0, dt_crit = " + fmt(dtCrit) + "] s (stable limit of the chain; set O.dt below it)");
  dynamics_.step(dt, collisions_.get());
}

void FabricEngine::enableCollisions(const ContactParams& p, BroadPhase broad) {
  p.validate();
  if (!collisions_) collisions_ = std::make_unique<CollisionStage>(p, broad);
  collisions_->setParams(p);
  collisions_->broadPhase = broad;
}

KinematicState FabricEngine::state() const {
  KinematicState s;
  s.pos = fabric_->pos, s.vel = fabric_->vel, s.step = dynamics_.stepCount(), s.time = dynamics_.time();
  s.flat = fabric_->secFlat, s.dir = fabric_->secDir, s.lastDt = dynamics_.lastDt();
  return s;
}

KinematicState FabricEngine::lastGoodState() const {
  KinematicState s;
  s.pos = dynamics_.lastGoodPos(), s.vel = dynamics_.lastGoodVel();
  s.flat = dynamics_.lastGoodFlat(), s.dir = dynamics_.lastGoodDir(), s.lastDt = dynamics_.lastGoodDt();
  s.step = dynamics_.lastGoodStep(), s.time = dynamics_.lastGoodTime();
  if (s.pos.empty()) return state();
  return s;
}

void FabricEngine::saveState(const std::string& path) {
  woven::saveState(path, state());
  if (collisions_) collisions_->invalidateCache();
}

void FabricEngine::setState(const KinematicState& s) {
  require(static_cast<Index>(s.pos.size()) == fabric_->nNodes() && s.vel.size() == s.pos.size(), "state",
          static_cast<double>(s.pos.size()), "a state with " + fmt(fabric_->nNodes()) + " nodes");
  fabric_->pos = s.pos;
  fabric_->vel = s.vel;
  if (s.flat.size() == s.pos.size() && s.dir.size() == s.pos.size()) fabric_->secFlat = s.flat, fabric_->secDir = s.dir;
  dynamics_.refreshForces();
  dynamics_.setClock(s.step, s.time, s.lastDt);
  if (collisions_) collisions_->invalidateCache();
}

}  // namespace woven
