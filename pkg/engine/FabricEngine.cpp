#include "engine/FabricEngine.hpp"
#include "core/Errors.hpp"
#include <cmath>
#include <string>

namespace woven {

FabricEngine::FabricEngine(Fabric fabric)
    : fabric_(std::make_unique<Fabric>(std::move(fabric))), dynamics_(*fabric_) {}

namespace {
// The collision stage seen by substep k of m of a step of `horizon`: its pass before the first
// substep's drift and its restitution after it, its rows solved again before the other substeps'
// drifts, its projection after the last one's; the bodies drift every substep, the books' takes
// and springs every substep.
class SubstepHook final : public StepHook {
 public:
  SubstepHook(CollisionStage& c, Real horizon, int m) : c_(c), horizon_(horizon), m_(m) {}
  int k = 0;
  Real beforeDrift(Fabric& f, Real dt) override {
    return k == 0 ? c_.beforeDrift(f, dt, horizon_) : c_.resolveAgain(f, dt, horizon_ * (m_ - k) / m_);
  }
  Real afterDrift(Fabric& f, Real dt) override { return c_.afterDrift(f, dt, k == 0, k == m_ - 1); }
  Real takeBodyWork() override { return c_.takeBodyWork(); }
  Real takeProjectionEnergy() override { return c_.takeProjectionEnergy(); }
  Real takeFrictionWork() override { return c_.takeFrictionWork(); }
  Real springEnergy() const override { return c_.springEnergy(); }

 private:
  CollisionStage& c_;
  Real horizon_;
  int m_;
};
}  // namespace

void FabricEngine::step(Real dt) {
  const Real dtMax = maxStep();
  // Refused before anything moves: a step above the central-difference limit grows without bound.
  if (!(std::isfinite(dt) && dt > 0 && dt <= dtMax * (1 + 1e-12)))  // message built only on failure
    throw ParameterError("dt", fmt(dt), "(0, " + std::string(substeps_ > 1 ? "substeps x " : "") + "dt_crit = " + fmt(dtMax) +
                                            "] s (stable limit of the chain; set O.dt below it)");
  if (substeps_ == 1) return dynamics_.step(dt, collisions_.get());
  const Real h = dt / substeps_;
  if (!collisions_) {
    for (int k = 0; k < substeps_; ++k) dynamics_.step(h, nullptr, k == substeps_ - 1);
    return;
  }
  SubstepHook hook(*collisions_, dt, substeps_);
  for (hook.k = 0; hook.k < substeps_; ++hook.k) dynamics_.step(h, &hook, hook.k == substeps_ - 1);
}

void FabricEngine::setSubsteps(int m) {
  if (m < 1 || m > 64) throw ParameterError("substeps", std::to_string(m), "[1, 64]");
  if (m > 1 && collisions_ && !CollisionStage::allowsSubsteps(collisions_->params()))
    throw ParameterError("substeps", std::to_string(m), CollisionStage::kSubstepsRange);
  substeps_ = m;
  applyRates();
}

void FabricEngine::setMultiRate(bool on) {
  multiRate_ = on;
  applyRates();
}

void FabricEngine::applyRates() {
  const Fabric& f = *fabric_;
  std::vector<std::uint8_t> slow;
  // Slow: stable at the longest step accepted, m x dt_crit, so that at any accepted dt the slow
  // elements keep the margin the fine ones keep (at safety 0.7 of m x dt_crit, 0.7 of their own
  // limit). Chosen at their limit instead (at dt itself), the CPs between 0.7 and 1 of theirs
  // drove the default cube scene's energy 67 % off. The 1e-9 takes the rounding off the design
  // case, a coarse CP exactly m fine ones long.
  if (multiRate_ && substeps_ > 1) slow = slowElements(f, maxStep() * (1 - 1e-9));
  dynamics_.setSlowElements(slow, substeps_);
  if (!collisions_) return;
  // A node is slow when every element it joins is: then only impulses change its velocity between
  // two passes.
  std::vector<std::uint8_t> slowNode;
  if (!dynamics_.slowElementMask().empty()) {
    slowNode.assign(f.nNodes(), 1);
    for (Index e = 0; e < f.nElems(); ++e)
      if (!dynamics_.slowElementMask()[e]) slowNode[f.elem0[e]] = slowNode[f.elem0[e] + 1] = 0;
  }
  collisions_->setSlowNodes(std::move(slowNode));
}

void FabricEngine::enableCollisions(const ContactParams& p, BroadPhase broad) {
  p.validate();
  if (substeps_ > 1 && !CollisionStage::allowsSubsteps(p))
    throw ParameterError("substeps", std::to_string(substeps_), CollisionStage::kSubstepsRange);
  if (!collisions_) collisions_ = std::make_unique<CollisionStage>(p, broad);
  collisions_->setParams(p);
  collisions_->broadPhase = broad;
  applyRates();  // the stage learns the slow nodes
}

KinematicState FabricEngine::state() const {
  KinematicState s;
  const Fabric& f = *fabric_;
  s.pos = f.pos, s.vel = f.vel, s.step = dynamics_.stepCount(), s.time = dynamics_.time();
  s.flat = f.secFlat, s.dir = f.secDir, s.lastDt = dynamics_.lastDt();
  s.topology = topologyFingerprint(f);
  s.yarns = f.nYarns();
  s.alive = f.alive, s.stiffness = f.stiffness, s.damping = f.damping;
  s.booksStarted = dynamics_.booksStarted(), s.springSeen = dynamics_.springSeen(), s.books = dynamics_.books();
  s.breakage = dynamics_.breakage().state();
  if (collisions_) s.contacts = collisions_->memory();
  return s;
}

KinematicState FabricEngine::lastGoodState() const {
  if (dynamics_.lastGoodPos().size() != fabric_->pos.size()) return state();
  KinematicState s = state();
  s.pos = dynamics_.lastGoodPos(), s.vel = dynamics_.lastGoodVel();
  s.flat = dynamics_.lastGoodFlat(), s.dir = dynamics_.lastGoodDir(), s.lastDt = dynamics_.lastGoodDt();
  s.step = dynamics_.lastGoodStep(), s.time = dynamics_.lastGoodTime();
  s.alive = dynamics_.lastGoodAlive(), s.stiffness = dynamics_.lastGoodStiffness(), s.damping = dynamics_.lastGoodDamping();
  s.books = dynamics_.lastGoodBooks(), s.springSeen = dynamics_.lastGoodSpringSeen(), s.booksStarted = true;
  s.breakage = dynamics_.lastGoodBreakage();
  s.contacts.clear();  // the stage's memory of the last good step is not kept
  return s;
}

void FabricEngine::saveState(const std::string& path) { woven::saveState(path, state()); }

void FabricEngine::checkState(const KinematicState& s) const {
  const Fabric& f = *fabric_;
  const Index n = f.nNodes(), ne = f.nElems();
  require(static_cast<Index>(s.pos.size()) == n && s.vel.size() == s.pos.size() && s.flat.size() == s.pos.size() &&
              s.dir.size() == s.pos.size(),
          "state", static_cast<double>(s.pos.size()), "a state with " + fmt(n) + " nodes");
  require(static_cast<Index>(s.alive.size()) == ne && s.stiffness.size() == s.alive.size() && s.damping.size() == s.alive.size(),
          "state", static_cast<double>(s.alive.size()), "a state with " + fmt(ne) + " elements");
  require(s.yarns == f.nYarns(), "state", s.yarns, "a state with " + fmt(f.nYarns()) + " yarns");
  if (s.topology != topologyFingerprint(f))
    throw ParameterError("state", "a state of another weave (topology fingerprint differs)",
                         "a state saved from this weave (same yarns, sections, rest lengths and masses)");
  require(s.step >= 0, "step", s.step, "[0, inf)");
  require(std::isfinite(s.time) && s.time >= 0, "time", s.time, "[0, inf) s");
  const Real dtCrit = dynamics_.criticalDt();
  require(std::isfinite(s.lastDt) && s.lastDt >= 0 && s.lastDt <= dtCrit * (1 + 1e-12), "last_dt", s.lastDt,
          "[0, dt_crit = " + fmt(dtCrit) + "] s");
  for (Index i = 0; i < n; ++i) {
    require(s.pos[i].allFinite() && s.vel[i].allFinite(), "state", i, "finite positions and velocities (node)");
    require(s.flat[i] >= 0 && s.flat[i] < 1, "state", s.flat[i], "section flattening eps in [0, 1)");
    require(s.dir[i].allFinite() && std::abs(s.dir[i].norm() - 1) <= 1e-6, "state", s.dir[i].norm(),
            "unit section directions");
  }
  for (Index e = 0; e < ne; ++e) {
    // A broken element has no stiffness or damping; a live one gets this engine's (setState).
    const bool ok = s.alive[e] == 1 ? std::isfinite(s.stiffness[e]) && s.stiffness[e] > 0
                                    : s.alive[e] == 0 && s.stiffness[e] == 0 && s.damping[e] == 0;
    require(ok, "state", e, "a finite stiffness where alive, 0 stiffness and damping where broken (element)");
  }
  Breakage::check(f, s.breakage, s.alive);
  if (collisions_ && !s.contacts.empty()) collisions_->checkMemory(f, s.contacts);
}

void FabricEngine::setState(const KinematicState& s) {
  checkState(s);  // everything first: nothing changes when the state is refused
  Fabric& f = *fabric_;
  f.pos = s.pos;
  f.vel = s.vel;
  f.secFlat = s.flat, f.secDir = s.dir;
  // Live elements take this weave's stiffness and damping (addYarn's formulas, so the same bits as
  // the run that saved the state when the materials are the same); broken ones none.
  f.alive = s.alive;
  for (Index e = 0; e < f.nElems(); ++e) {
    const YarnMaterial& m = f.materials[f.yarns[f.elemYarn[e]].material];
    const Real K = m.E * m.area / f.restLength[e], me = m.rho * m.area * f.restLength[e];
    f.stiffness[e] = s.alive[e] ? K : 0.0;
    f.damping[e] = s.alive[e] ? m.dampingRatio * std::sqrt(K * me) : 0.0;
  }
  dynamics_.restore(s.step, s.time, s.lastDt, s.books, s.booksStarted, s.springSeen, s.breakage);
  // The stage's memory goes on as the saving run's; a state without it (or of another build's
  // layout) is continued as a run that forgot it.
  if (collisions_ && (s.contacts.empty() || !collisions_->setMemory(f, s.contacts))) collisions_->invalidateCache();
}

}  // namespace woven
