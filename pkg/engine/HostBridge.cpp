#include "engine/HostBridge.hpp"
#include "engine/FabricEngine.hpp"
#include "core/Errors.hpp"
#include "shape/Section.hpp"

namespace woven {

void hostBodies(const FabricEngine& e, std::vector<HostBody>& out) {
  out.clear();
  if (const CollisionStage* st = e.collisions())
    for (const RigidBody& b : st->bodies) {
      HostBody h;
      h.id = b.id, h.dynamic = b.dynamic();
      out.push_back(h);
    }
}

void hostStep(FabricEngine& e, double dt, std::vector<HostBody>& bodies, bool rewind) {
  CollisionStage* st = e.collisions();
  const std::size_t nb = st ? st->bodies.size() : 0;
  if (bodies.size() != nb) throw std::logic_error("woven::hostStep: " + std::to_string(bodies.size()) + " bodies given for " + std::to_string(nb));
  for (std::size_t k = 0; k < nb; ++k) {
    const HostBody& h = bodies[k];
    RigidBody& b = st->bodies[k];
    b.setHostState(Vec3(h.pos[0], h.pos[1], h.pos[2]), Quat(h.ori[3], h.ori[0], h.ori[1], h.ori[2]),
                   Vec3(h.vel[0], h.vel[1], h.vel[2]), Vec3(h.angVel[0], h.angVel[1], h.angVel[2]), dt, rewind);
  }
  e.step(dt);
  for (std::size_t k = 0; k < nb; ++k) {
    const RigidBody& b = st->bodies[k];
    HostBody& h = bodies[k];
    h.dynamic = b.dynamic();
    if (!h.dynamic) continue;  // the host moves kinematic bodies itself
    const Vec3 L = b.angularMomentum();
    for (int i = 0; i < 3; ++i) h.pos[i] = b.pos[i], h.vel[i] = b.vel[i], h.angVel[i] = b.angVel[i], h.angMom[i] = L[i];
    h.ori[0] = b.ori.x(), h.ori[1] = b.ori.y(), h.ori[2] = b.ori.z(), h.ori[3] = b.ori.w();
  }
}

const char* coreBuildId() {
#ifdef WOVEN_BUILD_ID
  return WOVEN_BUILD_ID;
#else
  return "static";
#endif
}

long hostNodes(const FabricEngine& e) { return static_cast<long>(e.fabric().nNodes()); }

void hostTubes(const FabricEngine& e, HostTubes& out) {
  const Fabric& f = e.fabric();
  const SectionRule rule = e.collisions() ? e.collisions()->params().rule : SectionRule::ConstantArea;
  out.nodes.resize(8 * static_cast<std::size_t>(f.nNodes()));
  for (Index i = 0; i < f.nNodes(); ++i) {
    const SemiAxes s = semiAxes(f.secRadius[i], f.secFlat[i], rule);
    double* n = &out.nodes[8 * static_cast<std::size_t>(i)];
    n[0] = f.pos[i].x(), n[1] = f.pos[i].y(), n[2] = f.pos[i].z(), n[3] = s.a, n[4] = s.b;
    n[5] = f.secDir[i].x(), n[6] = f.secDir[i].y(), n[7] = f.secDir[i].z();
  }
  out.elements.clear(), out.strain.clear();
  for (Index el = 0; el < f.nElems(); ++el) {
    if (!f.alive[el]) continue;
    const Index a = f.elem0[el];
    out.elements.push_back(a);
    out.strain.push_back(((f.pos[a + 1] - f.pos[a]).norm() - f.restLength[el]) / f.restLength[el]);
  }
}

namespace {

const char* broadPhaseName(BroadPhase b) { return b == BroadPhase::YarnTree ? "tree" : b == BroadPhase::Grid ? "grid" : "sap"; }
const char* flatteningName(Flattening f) { return f == Flattening::Geometric ? "geometric" : f == Flattening::None ? "none" : "springs"; }

void toHost(const ContactParams& p, BroadPhase broad, HostStageParams& h) {
  h.sectionRule = sectionRuleName(p.rule), h.flattening = flatteningName(p.flattening), h.mcd = p.mcd;
  h.flattenPasses = p.flattenPasses, h.margin = p.margin;
  h.broadPhase = broadPhaseName(broad), h.skin = p.skin, h.selfExclude = static_cast<int>(p.selfExclude);
  h.yarnContacts = p.yarnContacts, h.threads = p.threads;
  h.model = p.model == ContactModel::Gap ? "gap" : "paper", h.cacheDistance = p.cacheDistance;
  h.penaltyStiffness = p.penaltyStiffness, h.penaltyDamping = p.penaltyDamping, h.sectionStiffness = p.sectionStiffness;
  h.response = p.response == Response::Impulse ? "impulse" : "penalty";
  h.sweepOrder = p.sweepOrder == SweepOrder::Coloured ? "coloured" : p.sweepOrder == SweepOrder::Blocked ? "blocked" : "sequential";
  h.restitution = p.restitution, h.friction = p.friction, h.bodyFriction = p.bodyFriction, h.tolerance = p.tolerance;
  h.positionCorrection = p.positionCorrection, h.correctionSlop = p.correctionSlop;
  h.projectionSlop = p.projectionSlop, h.projectionMaxMove = p.projectionMaxMove, h.projectionCheck = p.projectionCheck;
  h.maxIterations = p.maxIterations, h.projectionSweeps = p.projectionSweeps;
}

}  // namespace

void hostStageParams(const FabricEngine& e, HostStageParams& out) {
  const CollisionStage* st = e.collisions();
  if (!st) {
    hostStageDefaults(out);
    return;
  }
  toHost(st->params(), st->broadPhase, out);
  out.collisions = true;
  out.gridCell = st->grid.cellSize;
}

void hostStageDefaults(HostStageParams& out) {
  toHost(ContactParams(), BroadPhase::YarnTree, out);
  out.collisions = false, out.gridCell = 0;
}

void hostSetStageParams(FabricEngine& e, const HostStageParams& h) {
  if (!e.collisions())
    throw ParameterError("collisions", "off", "on: FabricEngine.enable_collisions(...) first (woven.contact.enable)");
  // The names first (each throws naming its parameter), then enableCollisions validates the numbers
  // before it changes anything.
  ContactParams p;
  p.rule = sectionRuleByName(h.sectionRule), p.flattening = flatteningByName(h.flattening);
  p.model = contactModelByName(h.model), p.response = responseByName(h.response), p.sweepOrder = sweepOrderByName(h.sweepOrder);
  const BroadPhase broad = broadPhaseByName(h.broadPhase);
  p.mcd = h.mcd, p.flattenPasses = h.flattenPasses, p.margin = h.margin;
  p.skin = h.skin, p.selfExclude = static_cast<Index>(h.selfExclude), p.yarnContacts = h.yarnContacts, p.threads = h.threads;
  p.cacheDistance = h.cacheDistance;
  p.penaltyStiffness = h.penaltyStiffness, p.penaltyDamping = h.penaltyDamping, p.sectionStiffness = h.sectionStiffness;
  p.restitution = h.restitution, p.friction = h.friction, p.bodyFriction = h.bodyFriction, p.tolerance = h.tolerance;
  p.positionCorrection = h.positionCorrection, p.correctionSlop = h.correctionSlop;
  p.projectionSlop = h.projectionSlop, p.projectionMaxMove = h.projectionMaxMove, p.projectionCheck = h.projectionCheck;
  p.maxIterations = h.maxIterations, p.projectionSweeps = h.projectionSweeps;
  e.enableCollisions(p, broad);
}

}  // namespace woven
