// Boost.Python bindings of the woven core (module woven._woven). Vectors are Eigen::Vector3d, the
// same C++ type as YADE's Vector3r, so YADE's converters pass YADE's Vector3 in and out unchanged.
// Bulk arrays go out as bytes (numpy.frombuffer in woven/), never as Python loops over nodes.
#include <boost/python.hpp>
#include <boost/python/stl_iterator.hpp>
#include "core/Errors.hpp"
#include "core/Parallel.hpp"
#include "core/ThreadCeiling.hpp"
#include "engine/FabricEngine.hpp"
#include "engine/Snapshot.hpp"
#include "geom/SeparatingAxis.hpp"
#include "shape/Cylinder.hpp"
#include "weave/WeaveBuilder.hpp"
#include <sys/stat.h>
#include <cstdio>
#include <cstring>
#include <memory>

namespace bp = boost::python;
using namespace woven;

namespace {

PyObject* g_instabilityType = nullptr;

void translateParameterError(const ParameterError& e) { PyErr_SetString(PyExc_ValueError, e.what()); }

void translateInstability(const InstabilityError& e) {
  PyObject* inst = PyObject_CallFunction(g_instabilityType, "s", e.what());
  if (!inst) return;
  PyObject_SetAttrString(inst, "step", PyLong_FromLong(e.step()));
  PyObject_SetAttrString(inst, "node", PyLong_FromLong(e.node()));
  PyObject_SetAttrString(inst, "element", PyLong_FromLong(e.element()));
  PyObject_SetAttrString(inst, "cause", PyUnicode_FromString(e.cause().c_str()));
  PyErr_SetObject(g_instabilityType, inst);
  Py_DECREF(inst);
}

template <class T>
bp::object bytesOf(const std::vector<T>& v) {
  return bp::object(bp::handle<>(PyBytes_FromStringAndSize(reinterpret_cast<const char*>(v.data()),
                                                           static_cast<Py_ssize_t>(v.size() * sizeof(T)))));
}

Pattern patternFromList(bp::object rows) {
  // Entries are read as numbers and must be exactly 0 or 1: an int conversion truncated 1.7 to 1.
  std::vector<std::vector<int>> m;
  for (bp::stl_input_iterator<bp::object> r(rows), end; r != end; ++r) {
    std::vector<int> row;
    for (bp::stl_input_iterator<bp::object> c(*r), e2; c != e2; ++c) {
      bp::extract<double> x(*c);
      if (!x.check()) throw ParameterError("pattern", "a non-numeric entry", "entries 0 or 1");
      const double v = x();
      if (v != 0 && v != 1) throw ParameterError("pattern", "entry " + fmt(v), "entries 0 or 1 (exactly)");
      row.push_back(static_cast<int>(v));
    }
    m.push_back(row);
  }
  return Pattern(m);
}
bp::list patternMatrix(const Pattern& p) {
  bp::list out;
  for (const auto& r : p.matrix()) {
    bp::list row;
    for (int v : r) row.append(v);
    out.append(row);
  }
  return out;
}

Index addYarn(Fabric& f, bp::object points, const YarnMaterial& m, const YarnSection& s) {
  Vec3Array pts;
  for (bp::stl_input_iterator<Vec3> it(points), end; it != end; ++it) pts.push_back(*it);
  return f.addYarn(pts, m, s);
}

std::shared_ptr<FabricEngine> makeEngine(const Fabric& f) { return std::make_shared<FabricEngine>(f); }

bp::tuple buildWeavePy(const WeaveParams& p) {
  Weave w = buildWeave(p);
  bp::list warp, weft;
  for (Index y : w.warpYarns) warp.append(y);
  for (Index y : w.weftYarns) weft.append(y);
  return bp::make_tuple(std::make_shared<FabricEngine>(std::move(w.fabric)), w.summary, warp, weft);
}

// --- FabricEngine helpers ---
Vec3 nodePos(FabricEngine& e, Index i) { e.fabric().checkNode(i); return e.fabric().pos[i]; }
Vec3 nodeVel(FabricEngine& e, Index i) { e.fabric().checkNode(i); return e.dynamics().syncVelocity(i); }
void setNodePos(FabricEngine& e, Index i, const Vec3& x) {
  e.fabric().checkNode(i);
  require(x.allFinite() && x.cwiseAbs().maxCoeff() <= 1e3, "position", x.allFinite() ? x.cwiseAbs().maxCoeff() : NAN,
          "finite coordinates within [-1e3, 1e3] m");
  // The moved node changes the elastic energy: it joins the initial energy (bookEdit), else the
  // blow-up check would take the edit for an instability.
  const bool started = e.dynamics().booksStarted();
  const Real before = started ? e.dynamics().energy().total() : 0.0;
  e.fabric().pos[i] = x;
  e.dynamics().refreshForces();
  if (started) e.dynamics().bookEdit(e.dynamics().energy().total() - before);
}
void setNodeVel(FabricEngine& e, Index i, const Vec3& v) {
  e.fabric().checkNode(i);
  require(v.allFinite() && v.norm() <= 1e5, "velocity", v.norm(), "finite, |v| <= 1e5 m/s");
  // The kinetic energy the edit adds joins the initial energy (see setNodePos).
  const Real m = e.fabric().mass[i];
  const Real before = 0.5 * m * e.dynamics().syncVelocity(i).squaredNorm();
  e.fabric().vel[i] = v;
  e.dynamics().bookEdit(0.5 * m * e.dynamics().syncVelocity(i).squaredNorm() - before);
}
Real nodeMass(FabricEngine& e, Index i) { e.fabric().checkNode(i); return e.fabric().mass[i]; }
bp::tuple elementNodes(FabricEngine& e, Index k) {
  e.fabric().checkElem(k);
  return bp::make_tuple(e.fabric().elem0[k], e.fabric().elem0[k] + 1);
}
bp::dict yarnInfo(FabricEngine& e, Index y) {
  require(y >= 0 && y < e.fabric().nYarns(), "yarn", y, "[0, " + fmt(e.fabric().nYarns() - 1) + "]");
  const Yarn& Y = e.fabric().yarns[y];
  const YarnMaterial& M = e.fabric().materials[Y.material];
  bp::dict d;
  d["first_node"] = Y.firstNode, d["n_nodes"] = Y.nNodes, d["first_element"] = Y.firstElem, d["n_elements"] = Y.nElems;
  d["family"] = Y.family == YarnFamily::Warp ? "warp" : (Y.family == YarnFamily::Weft ? "weft" : "free");
  d["width"] = Y.section.width, d["thickness"] = Y.section.thickness;
  d["E"] = M.E, d["rho"] = M.rho, d["area"] = M.area, d["damping"] = M.dampingRatio;
  d["failure_strain"] = M.failureStrain, d["tension_only"] = M.tensionOnly, d["bending"] = M.bending;
  return d;
}
bp::dict energyDict(FabricEngine& e) {
  const EnergyBooks b = e.dynamics().energy();
  bp::dict d;
  d["kinetic"] = b.kinetic, d["elastic"] = b.elastic, d["damped"] = b.damped, d["work"] = b.work;
  d["initial"] = b.initial, d["contact"] = b.contact, d["friction"] = b.friction, d["contact_input"] = b.contactInput;
  d["released"] = b.released, d["body_work"] = b.bodyWork, d["spring"] = b.spring, d["projection"] = b.projection;
  d["balance_error"] = b.balanceError();
  return d;
}
Vec3 reactionOf(FabricEngine& e, bp::object nodes) {
  std::vector<Index> v;
  for (bp::stl_input_iterator<Index> it(nodes), end; it != end; ++it) v.push_back(*it);
  return e.dynamics().reaction(v);
}
bp::object syncVelocities(FabricEngine& e) {
  Vec3Array v(e.fabric().nNodes());
  for (Index i = 0; i < e.fabric().nNodes(); ++i) v[i] = e.dynamics().syncVelocity(i);
  return bytesOf(v);
}
void runSteps(FabricEngine& e, Real dt, long n) {
  // Past 2^31 a count is no count of steps (2^31 steps of the smallest fabric: hours; the fuzz's
  // 2^31 ran on as a hang): the integer arguments' range.
  require(n >= 0 && n <= 2147483647L, "steps", n, "[0, 2^31)");
  for (long k = 0; k < n; ++k) e.step(dt);
}
void saveStatePy(FabricEngine& e, const std::string& path, bool lastGood) {
  if (lastGood) saveState(path, e.lastGoodState());
  else e.saveState(path);
}
void loadStatePy(FabricEngine& e, const std::string& path) {
  // StateIO reads the whole file before it checks it: an endless device (/dev/zero) or a huge file
  // that is no state ran out of memory (a MemoryError with no message). A state file is a
  // regular file that starts with WOVENST: anything else is refused here, naming it, before a byte
  // more is read. (A missing file is left to loadState, which says why it cannot be opened.)
  struct stat st;
  if (path.find('\0') == std::string::npos && ::stat(path.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode))
      throw ParameterError("path", "'" + path + "'", std::string("a woven state file: this is ") +
                                                         (S_ISDIR(st.st_mode) ? "a folder" : S_ISCHR(st.st_mode) ? "a character device" :
                                                          S_ISFIFO(st.st_mode) ? "a pipe" : "not a regular file") +
                                                         ", not a woven state");
    char head[7] = {};
    std::FILE* in = std::fopen(path.c_str(), "rb");
    const std::size_t got = in ? std::fread(head, 1, sizeof(head), in) : 0;
    if (in) std::fclose(in);
    if (in && (got < sizeof(head) || std::memcmp(head, "WOVENST", sizeof(head)) != 0))
      throw ParameterError("path", "'" + path + "'", "a woven state file (it does not start with WOVENST: not a woven state)");
  }
  // Read into a temporary and checked whole (StateIO, FabricEngine::checkState), then committed.
  e.setState(loadState(path, e.fabric().nNodes()));
}
void fixNode(FabricEngine& e, Index i) { e.dynamics().fix(i); }
void prescribe(FabricEngine& e, Index i, const Vec3& v) { e.dynamics().prescribeVelocity(i, v); }
void releaseNode(FabricEngine& e, Index i) { e.dynamics().release(i); }
void pointForce(FabricEngine& e, Index i, const Vec3& F) { e.dynamics().setPointForce(i, F); }
void gravity(FabricEngine& e, const Vec3& g) { e.dynamics().setBodyAcceleration(g); }
Vec3 getGravity(FabricEngine& e) { return e.dynamics().loads().bodyAcceleration; }
Real blowup(FabricEngine& e) { return e.dynamics().limits.blowupFactor; }
void setBlowup(FabricEngine& e, Real f) {
  require(std::isfinite(f) && f > 0, "blowup_factor", f, "(0, inf) (below 1 only to test the check)");
  e.dynamics().limits.blowupFactor = f;
}
long checkpointInterval(FabricEngine& e) { return e.dynamics().limits.checkpointInterval; }
void setCheckpointInterval(FabricEngine& e, long k) {
  require(k >= 1, "checkpoint_interval", k, "[1, inf) steps");
  e.dynamics().limits.checkpointInterval = k;
}
bool isKinematic(FabricEngine& e, Index i) { e.fabric().checkNode(i); return e.dynamics().isKinematic(i); }

// --- collisions ---
void enableCollisionsPy(FabricEngine& e, Real restitution, Real friction, Real bodyFriction, Real mcd, const std::string& rule, Real margin,
                        Real tolerance, int maxIterations, int flattenPasses, Real positionCorrection,
                        Real correctionSlop, Index selfExclude, const std::string& broad, Real skin, int threads,
                        bool yarnContacts, Real cacheDistance, const std::string& response, Real penaltyStiffness,
                        Real penaltyDamping, const std::string& flattening, Real sectionStiffness,
                        const std::string& model, int projectionSweeps, Real projectionSlop, Real projectionMaxMove,
                        const std::string& sweepOrder, Real projectionCheck, const std::string& crossings,
                        Real solverTolerance) {
  ContactParams p;
  p.crossings = crossingsByName(crossings), p.solverTolerance = solverTolerance;
  p.sweepOrder = sweepOrderByName(sweepOrder);
  p.model = contactModelByName(model), p.projectionSweeps = projectionSweeps, p.projectionSlop = projectionSlop;
  p.projectionMaxMove = projectionMaxMove, p.projectionCheck = projectionCheck;
  p.restitution = restitution, p.friction = friction, p.bodyFriction = bodyFriction, p.mcd = mcd, p.rule = sectionRuleByName(rule);
  p.margin = margin, p.tolerance = tolerance, p.maxIterations = maxIterations, p.flattenPasses = flattenPasses;
  p.positionCorrection = positionCorrection, p.correctionSlop = correctionSlop, p.selfExclude = selfExclude;
  p.skin = skin, p.threads = threads, p.yarnContacts = yarnContacts, p.cacheDistance = cacheDistance;
  p.response = responseByName(response), p.penaltyStiffness = penaltyStiffness, p.penaltyDamping = penaltyDamping;
  p.flattening = flatteningByName(flattening), p.sectionStiffness = sectionStiffness;
  e.enableCollisions(p, broadPhaseByName(broad));
}
CollisionStage& stageOf(FabricEngine& e) {
  if (!e.collisions())
    throw ParameterError("collisions", "off", "on: call FabricEngine.enable_collisions(...) first");
  return *e.collisions();
}
bp::dict collisionStats(FabricEngine& e) {
  const CollisionStats& s = stageOf(e).stats;
  bp::dict d;
  d["steps"] = s.steps, d["broad_phases"] = s.broadPhases, d["partial_broad_phases"] = s.partialBroadPhases, d["candidates"] = s.candidates, d["contacts"] = s.contacts, d["moving"] = s.moving, d["cached"] = s.cached;
  d["flattened"] = s.flattened, d["flatten_passes"] = s.flattenPasses;
  d["impulse_rows"] = s.impulses.rows, d["iterations"] = s.impulses.iterations, d["residual"] = s.impulses.residual;
  d["unresolved"] = s.impulses.unresolved, d["penetration"] = s.penetration, d["max_penetration"] = s.maxPenetration;
  d["unresolved_band"] = s.impulses.unresolvedBand, d["skipped_updates"] = s.impulses.skipped;
  d["renewed"] = s.renewed;
  d["max_unresolved"] = s.maxUnresolved, d["max_residual"] = s.maxResidual;
  d["total_rows"] = s.totalRows, d["total_sweeps"] = s.totalSweeps, d["total_unresolved"] = s.totalUnresolved;
  d["correction_energy"] = s.correctionEnergy;
  d["mean_penetration"] = s.meanPenetration, d["overlapping"] = s.overlapping;
  d["deepest_pair"] = bp::make_tuple(s.deepestA, s.deepestB);
  d["overlap_sum"] = s.overlapSum, d["overlap_count"] = s.overlapCount;
  d["body_overlap_sum"] = s.bodyOverlapSum, d["body_overlap_count"] = s.bodyOverlapCount;
  d["projection_sweeps"] = s.projection.sweeps, d["projection_pushed"] = s.projection.pushed;
  d["projection_step_energy"] = s.projection.energy, d["projection_energy"] = s.projectionEnergy;
  d["check_pushed"] = s.check.pushed, d["checks"] = s.checks, d["max_checked"] = s.maxChecked;
  d["projection_overlap_left"] = s.projection.overlapLeft;
  d["force_rows"] = s.forces.rows, d["spring_energy"] = s.springEnergy, d["force_dissipated"] = s.forces.dissipated;
  d["seconds_refit"] = s.seconds[0], d["seconds_broad"] = s.seconds[1];
  d["seconds_narrow"] = s.seconds[2], d["seconds_respond"] = s.seconds[3], d["seconds_project"] = s.seconds[4];
  d["tree_rebuilt_nodes"] = stageOf(e).tree.stats.rebuiltNodes;
  d["body_contacts"] = s.bodyContacts, d["body_penetration"] = s.bodyPenetration, d["deepest_body_cp"] = s.deepestBodyCP;
  d["max_body_penetration"] = s.maxBodyPenetration, d["body_lists"] = stageOf(e).bodyCollider.rebuilds;
  // The persistent crossings (ContactParams::crossings): live now, listed as contacts in the last
  // step, formed and handed back (by rule) since the start, footprint moves since the start.
  d["crossings"] = s.crossings.live, d["crossing_contacts"] = s.crossings.listed;
  d["crossings_formed"] = s.crossings.formed, d["crossings_moved"] = s.crossings.moved;
  d["handed_back_break"] = s.crossings.handedBack[0], d["handed_back_separation"] = s.crossings.handedBack[1];
  d["handed_back_turn"] = s.crossings.handedBack[2], d["handed_back_slide"] = s.crossings.handedBack[3];
  d["handed_back_kink"] = s.crossings.handedBack[4];
  return d;
}

// --- breakage ---
void enableBreakage(FabricEngine& e, Real strain, Real filterLength, Real weibull, long seed) {
  require(seed >= 0, "seed", seed, "[0, 2^63)");
  BreakageParams p;
  p.enabled = true, p.threshold = strain, p.filterLength = filterLength, p.weibullModulus = weibull;
  p.seed = static_cast<std::uint64_t>(seed);
  e.dynamics().configureBreakage(p);
}
bp::list breakLog(FabricEngine& e) {
  bp::list out;
  for (const BreakEvent& b : e.dynamics().breakage().log()) {
    bp::dict d;
    d["step"] = b.step, d["time"] = b.time, d["yarn"] = b.yarn, d["element"] = b.element;
    d["position"] = b.position, d["strain"] = b.strain, d["raw_strain"] = b.rawStrain, d["energy"] = b.energy;
    out.append(d);
  }
  return out;
}

// --- rigid bodies (YADE's projectile, clamps) ---
CollisionStage& bodyStage(FabricEngine& e) {
  if (!e.collisions())
    throw ParameterError("collisions", "off", "on: rigid bodies collide through the collision stage (enable_collisions)");
  return *e.collisions();
}
RigidBody& bodyAt(FabricEngine& e, int k) {
  auto& b = bodyStage(e).bodies;
  require(k >= 0 && k < static_cast<int>(b.size()), "index", k, "[0, " + fmt(static_cast<long>(b.size()) - 1) + "]");
  return b[k];
}
// A cylinder's (radius, half_length, chisel_angle, land_half_width) from a Python sequence.
Eigen::Matrix<Real, 4, 1> cylinderDims(bp::object d) {
  require(bp::len(d) == 4, "parts", static_cast<Real>(bp::len(d)),
          "a cylinder's (radius [m], half_length [m], chisel_angle [rad], land_half_width [m])");
  Eigen::Matrix<Real, 4, 1> v;
  for (int k = 0; k < 4; ++k) v[k] = bp::extract<Real>(d[k]);
  return v;
}
// parts: list of ('box', half_extents Vector3, offset Vector3, Quaternion), ('sphere', radius, offset, Quaternion)
// or ('cylinder', (radius, half_length, chisel_angle, land_half_width), offset, Quaternion)
int addBody(FabricEngine& e, long id, bp::object parts, Real mass, const Vec3& inertia, const Vec3& pos, const Quat& ori,
            const Vec3& vel, const Vec3& angVel) {
  RigidBody b;
  b.id = id, b.mass = mass, b.inertia = inertia, b.pos = pos, b.ori = ori, b.vel = vel, b.angVel = angVel;
  for (bp::stl_input_iterator<bp::object> it(parts), end; it != end; ++it) {
    bp::object t = *it;
    RigidPart p;
    const std::string kind = bp::extract<std::string>(t[0]);
    if (kind == "box") p.type = RigidPart::Type::Box, p.halfSize = bp::extract<Vec3>(t[1]);
    else if (kind == "sphere") p.type = RigidPart::Type::Sphere, p.radius = bp::extract<Real>(t[1]);
    else if (kind == "cylinder") {
      // ('cylinder', (radius, half_length, chisel_angle, land_half_width), offset, ori): axis z, nose +z.
      p.type = RigidPart::Type::Cylinder;
      const Eigen::Matrix<Real, 4, 1> dims = cylinderDims(t[1]);
      p.radius = dims[0], p.halfLength = dims[1], p.chiselAngle = dims[2], p.landHalfWidth = dims[3];
      require(bodyStage(e).params().model == ContactModel::Gap, "parts", 0,
              "box or sphere parts with contact_model 'paper' (a cylinder has the gap model's form only)");
    } else if (kind == "triangle" || kind == "facet") {
      // ('triangle' | 'facet', (v0, v1, v2), offset, ori): a closed mesh's face (outward by the
      // corners' order: counter-clockwise seen from outside) or a lone facet, outside on both faces.
      p.type = RigidPart::Type::Triangle, p.twoSided = kind == "facet";
      bp::object v = t[1];
      require(bp::len(v) == 3, "parts", static_cast<Real>(bp::len(v)), "a triangle's three corners (v0, v1, v2) [m]");
      for (int k = 0; k < 3; ++k) p.vert[k] = bp::extract<Vec3>(v[k]);
      require(bodyStage(e).params().model == ContactModel::Gap, "parts", 0,
              "box or sphere parts with contact_model 'paper' (a triangle has the gap model's form only)");
    } else throw ParameterError("parts", "'" + kind + "'", "'box', 'sphere', 'cylinder', 'triangle' or 'facet' parts");
    p.offset = bp::extract<Vec3>(t[2]);
    p.ori = bp::extract<Quat>(t[3]);
    b.parts.push_back(p);
  }
  b.validate();
  // The same YADE body twice would take every impulse twice.
  for (const RigidBody& o : bodyStage(e).bodies)
    require(o.id != id, "id", id, "a YADE body not coupled yet (each body once)");
  bodyStage(e).bodies.push_back(b);
  // A body that starts inside the fabric would be pushed out by the first step's rows and projection
  // at any cost: refused, naming it (add_body used to take one without a word; coupling's
  // check covered only woven.coupling.couple).
  const int k = static_cast<int>(bodyStage(e).bodies.size()) - 1;
  const Real overlap = bodyStage(e).bodyOverlap(e.fabric(), k);
  if (overlap > 0) {
    bodyStage(e).bodies.pop_back();
    throw ParameterError("body", "id " + fmt(id) + " at (" + fmt(pos.x()) + ", " + fmt(pos.y()) + ", " + fmt(pos.z()) + ") m",
                         "a body clear of every yarn (it starts inside the fabric: overlap " + fmt(overlap) + " m)");
  }
  return k;
}
bp::dict bodyDict(FabricEngine& e, int k) {
  const RigidBody& b = bodyAt(e, k);
  bp::dict d;
  d["id"] = b.id, d["mass"] = b.mass, d["inertia"] = b.inertia, d["pos"] = b.pos, d["ori"] = b.ori;
  d["vel"] = b.vel, d["ang_vel"] = b.angVel, d["kinetic_energy"] = b.kineticEnergy(), d["parts"] = b.parts.size();
  d["friction"] = b.friction;
  return d;
}
// A body's own Coulomb coefficient with the yarns (negative: the law's body_friction again).
void setBodyFriction(FabricEngine& e, int k, Real mu) {
  RigidBody& b = bodyAt(e, k);
  require(std::isfinite(mu) && mu <= 2, "body friction", mu, "[0, 2], or negative for the law's body_friction");
  require(!(mu > 0 && bodyStage(e).params().response == Response::Penalty), "body friction", mu,
          "0 with response 'penalty' (Coulomb friction acts in the impulse rows only)");
  b.friction = mu < 0 ? -1.0 : mu;
}
void setBodyState(FabricEngine& e, int k, const Vec3& pos, const Quat& ori, const Vec3& vel, const Vec3& angVel) {
  RigidBody& b = bodyAt(e, k);
  RigidBody c = b;
  c.pos = pos, c.ori = ori, c.vel = vel, c.angVel = angVel;
  c.validate();  // nothing changes on bad input
  // Nor a pose deeper in the fabric than where the body is now (a body in contact may move within
  // its overlap, or out of it; one set into the yarns would be pushed out at any cost).
  const Real before = bodyStage(e).bodyOverlap(e.fabric(), k);
  std::swap(b, c);
  const Real after = bodyStage(e).bodyOverlap(e.fabric(), k);
  if (after > std::max(before, Real(0))) {
    std::swap(b, c);
    throw ParameterError("pos", "(" + fmt(pos.x()) + ", " + fmt(pos.y()) + ", " + fmt(pos.z()) + ") m of body " + fmt(k) +
                                    " (id " + fmt(b.id) + ")",
                         "a pose no deeper in the fabric than the body's present one (overlap " + fmt(std::max(before, Real(0))) +
                             " m; this pose: " + fmt(after) + " m)");
  }
}
// One step coupled with YADE: each body's state is read from O.bodies[id].state; with `rewind`
// (NewtonIntegrator ran before this engine in the same iteration, so YADE already moved the body
// from x_n to x_n + dt v) the pose is taken back to x_n; the fabric steps with the bodies; their new
// pose and velocities are written back. A few attribute reads and writes per body, none per node.
void yadeStep(FabricEngine& e, Real dt, bp::object yadeBodies, bool rewind) {
  CollisionStage* st = e.collisions();
  std::vector<bp::object> states;
  if (st) {
    for (RigidBody& b : st->bodies) {
      bp::object s = yadeBodies[b.id].attr("state");
      states.push_back(s);
      b.setHostState(bp::extract<Vec3>(s.attr("pos")), bp::extract<Quat>(s.attr("ori")),
                     bp::extract<Vec3>(s.attr("vel")), bp::extract<Vec3>(s.attr("angVel")), dt, rewind);
    }
  }
  e.step(dt);
  if (st) {
    for (std::size_t k = 0; k < st->bodies.size(); ++k) {
      const RigidBody& b = st->bodies[k];
      if (!b.dynamic()) continue;  // YADE moves kinematic bodies itself
      bp::object s = states[k];
      s.attr("pos") = b.pos;
      s.attr("ori") = b.ori;
      s.attr("vel") = b.vel;
      s.attr("angVel") = b.angVel;
      // YADE integrates an aspherical body (a clump) through its angular momentum: keep them together.
      s.attr("angMom") = b.angularMomentum();
    }
  }
}
bp::object candidatePairsPy(FabricEngine& e, const std::string& broad) {
  std::vector<CPPair> pairs;
  stageOf(e).candidatePairs(e.fabric(), broadPhaseByName(broad), pairs);
  std::vector<Index> flat;
  for (const CPPair& q : pairs) flat.push_back(q.a), flat.push_back(q.b);
  return bytesOf(flat);
}
bp::object contactsPy(FabricEngine& e) {  // cpA, cpB, gap [m], normal x y z, sA, sB, kind, hA, hB [m] per contact of the last step
  std::vector<Real> out;
  for (const CPContact& c : stageOf(e).contacts())
    out.insert(out.end(), {Real(c.cpA), Real(c.cpB), c.gap, c.normal.x(), c.normal.y(), c.normal.z(), c.sA, c.sB,
                           Real(static_cast<int>(c.kind)), c.hA, c.hB});
  return bytesOf(out);
}
bp::object crossingsPy(FabricEngine& e) {  // cpA, sA, cpB, sB, normal x y z, measure [m], impulse [N s] per persistent crossing
  std::vector<Real> out;
  for (const Crossing& x : stageOf(e).crossings().crossings())
    out.insert(out.end(), {Real(x.a.cp), x.a.s, Real(x.b.cp), x.b.s, x.normal.x(), x.normal.y(), x.normal.z(), x.measure,
                           x.lambda});
  return bytesOf(out);
}
bp::object semiAxesPy(FabricEngine& e) {  // a, b per node [m] with the stage's section rule
  const Fabric& f = e.fabric();
  const SectionRule rule = stageOf(e).params().rule;
  std::vector<Real> out;
  for (Index k = 0; k < f.nNodes(); ++k) {
    const SemiAxes s = semiAxes(f.secRadius[k], f.secFlat[k], rule);
    out.push_back(s.a), out.push_back(s.b);
  }
  return bytesOf(out);
}

// The single-pair helpers take the ranges of the scenes' inputs (README, Parameters): positions within
// +-1e3 m, sizes up to 1e3 m, velocities up to 1e5 m/s; a step of at most 1 s (woven's are ~1e-8 s).
// Past them (1e300) the separating-axis arithmetic overflows into inf and NaN answers (found by fuzzing).
OBB makeObb(const Vec3& c, const Mat3& axes, const Vec3& e) {
  require(c.allFinite() && c.cwiseAbs().maxCoeff() <= 1e3, "centre", c.cwiseAbs().maxCoeff(), "coordinates within +-1e3 m");
  require(axes.allFinite(), "axes", 0, "finite values");
  require((axes.transpose() * axes - Mat3::Identity()).cwiseAbs().maxCoeff() < 1e-9 && axes.determinant() > 0, "axes",
          axes.determinant(), "a rotation matrix (orthonormal columns A0, A1, A2, right-handed)");
  require(e.allFinite() && e.minCoeff() >= 0 && e.maxCoeff() <= 1e3, "extents", e.minCoeff() < 0 ? e.minCoeff() : e.maxCoeff(),
          "[0, 1e3] m (half-extents)");
  OBB b;
  b.centre = c, b.axes = axes, b.extent = e;
  return b;
}
bp::dict contactDict(const BoxContact& c) {
  bp::dict d;
  d["overlap"] = c.overlap, d["normal"] = c.normal, d["depth"] = c.depth, d["axis"] = c.axis;
  bp::list pts;
  for (int i = 0; i < c.nPoints; ++i)
    pts.append(bp::make_tuple(c.points[i].onA, c.points[i].onB, c.points[i].depth));
  d["points"] = pts;
  return d;
}
bp::dict obbContactPy(const Vec3& ca, const Mat3& Aa, const Vec3& ea, const Vec3& cb, const Mat3& Ab, const Vec3& eb) {
  return contactDict(obbContact(makeObb(ca, Aa, ea), makeObb(cb, Ab, eb)));
}
bp::dict obbFirstContactPy(const Vec3& ca, const Mat3& Aa, const Vec3& ea, const Vec3& va, const Vec3& cb,
                           const Mat3& Ab, const Vec3& eb, const Vec3& vb, Real dt) {
  require(std::isfinite(dt) && dt >= 0 && dt <= 1, "dt", dt, "[0, 1] s");
  require(va.allFinite() && va.norm() <= 1e5, "velocity_a", va.norm(), "|v| <= 1e5 m/s");
  require(vb.allFinite() && vb.norm() <= 1e5, "velocity_b", vb.norm(), "|v| <= 1e5 m/s");
  const SweptContact s = obbFirstContact(makeObb(ca, Aa, ea), va, makeObb(cb, Ab, eb), vb, dt);
  bp::dict d;
  d["hit"] = s.hit, d["time"] = s.time, d["contact"] = contactDict(s.contact);
  return d;
}

}  // namespace

BOOST_PYTHON_MODULE(_woven) {
  bp::docstring_options doc(true, true, false);
  g_instabilityType = PyErr_NewExceptionWithDoc(
      "woven._woven.InstabilityError",
      "The simulation went unstable; attributes step, node, element (-1 if none) and cause.",
      PyExc_RuntimeError, nullptr);
  bp::scope().attr("InstabilityError") = bp::handle<>(bp::borrowed(g_instabilityType));
  bp::register_exception_translator<ParameterError>(&translateParameterError);
  bp::register_exception_translator<InstabilityError>(&translateInstability);

  bp::class_<Pattern>("Pattern", "Interlacing matrix: entry (i, j) = 1 where warp i passes over weft j.", bp::no_init)
      .def("__init__", bp::make_constructor(+[](bp::object m) { return std::make_shared<Pattern>(patternFromList(m)); }))
      .def("plain", &Pattern::plain).staticmethod("plain")
      .def("twill", &Pattern::twill, (bp::arg("over"), bp::arg("under"))).staticmethod("twill")
      .def("satin", &Pattern::satin, (bp::arg("n"), bp::arg("step"))).staticmethod("satin")
      .def("basket", &Pattern::basket, (bp::arg("n"))).staticmethod("basket")
      .def("by_name", &Pattern::byName, (bp::arg("name"), bp::arg("a") = 2, bp::arg("b") = 1)).staticmethod("by_name")
      .add_property("rows", &Pattern::rows, "warp yarns in the repeat")
      .add_property("cols", &Pattern::cols, "weft yarns in the repeat")
      .add_property("matrix", &patternMatrix);

  bp::class_<YarnMaterial>("YarnMaterial", "Axial material of a yarn (SI).")
      .def_readwrite("E", &YarnMaterial::E, "Young's modulus [Pa]")
      .def_readwrite("rho", &YarnMaterial::rho, "fibre density [kg/m^3]")
      .def_readwrite("area", &YarnMaterial::area, "fibre cross-section area [m^2]")
      .def_readwrite("damping", &YarnMaterial::dampingRatio, "damping ratio of the highest chain mode [-]")
      .def_readwrite("failure_strain", &YarnMaterial::failureStrain, "strain at break [-]")
      .def_readwrite("tension_only", &YarnMaterial::tensionOnly, "no axial force while slack [bool]")
      .def_readwrite("bending", &YarnMaterial::bending, "bending stiffness EI [N m^2] (0: none)")
      .def("validate", &YarnMaterial::validate, (bp::arg("prefix") = ""));
  bp::class_<YarnSection>("YarnSection", "Elliptic section at rest (SI).")
      .def_readwrite("width", &YarnSection::width, "[m]")
      .def_readwrite("thickness", &YarnSection::thickness, "[m]");

  bp::class_<PeirceState>("PeirceState", "Peirce's plain-weave geometry of one yarn family (SI).")
      .def_readonly("p", &PeirceState::p).def_readonly("h", &PeirceState::h).def_readonly("D", &PeirceState::D)
      .def_readonly("theta", &PeirceState::theta).def_readonly("l", &PeirceState::l)
      .add_property("crimp", &PeirceState::crimp);
  bp::def("peirce_from_height", &peirceFromHeight, (bp::arg("p"), bp::arg("h"), bp::arg("D")),
          "Peirce geometry from spacing p [m], crimp height h [m] and D = d1 + d2 [m].");
  bp::def("peirce_from_crimp", &peirceFromCrimp, (bp::arg("p"), bp::arg("crimp"), bp::arg("D")),
          "Peirce geometry from spacing p [m], crimp [-] and D = d1 + d2 [m].");

  bp::def("obb_contact", &obbContactPy,
          (bp::arg("centre_a"), bp::arg("axes_a"), bp::arg("extents_a"), bp::arg("centre_b"), bp::arg("axes_b"),
           bp::arg("extents_b")),
          "Separating-axis test of two oriented boxes (centre [m], Matrix3 whose columns are the axes, "
          "half-extents [m]): dict overlap, normal (A to B), depth [m] (exact 15-axis minimum), axis "
          "(0-2 face of A, 3-5 face of B, 6+3i+j edge A_i x B_j), points [(on A, on B, depth)].");
  bp::def("obb_first_contact", &obbFirstContactPy,
          (bp::arg("centre_a"), bp::arg("axes_a"), bp::arg("extents_a"), bp::arg("velocity_a"), bp::arg("centre_b"),
           bp::arg("axes_b"), bp::arg("extents_b"), bp::arg("velocity_b"), bp::arg("dt")),
          "Moving separating-axis test over [0, dt] s with constant velocities [m/s]: dict hit, time [s] "
          "(first contact), contact (as obb_contact, at that time).");

  bp::class_<WeaveParams>("WeaveParams", "Weave builder parameters (SI); see woven.weave for the keys.")
      .def_readwrite("pattern", &WeaveParams::pattern)
      .def_readwrite("nx", &WeaveParams::nx).def_readwrite("ny", &WeaveParams::ny)
      .def_readwrite("warp_spacing", &WeaveParams::warpSpacing).def_readwrite("weft_spacing", &WeaveParams::weftSpacing)
      .def_readwrite("warp_section", &WeaveParams::warpSection).def_readwrite("weft_section", &WeaveParams::weftSection)
      .def_readwrite("warp_material", &WeaveParams::warpMaterial).def_readwrite("weft_material", &WeaveParams::weftMaterial)
      .def_readwrite("warp_crimp", &WeaveParams::warpCrimp).def_readwrite("weft_crimp", &WeaveParams::weftCrimp)
      .def_readwrite("cp_per_span", &WeaveParams::cpPerSpan)
      .def_readwrite("fine_radius", &WeaveParams::fineRadius).def_readwrite("cp_coarse", &WeaveParams::cpCoarse)
      .def_readwrite("fine_x", &WeaveParams::fineX).def_readwrite("fine_y", &WeaveParams::fineY)
      .def("validate", &WeaveParams::validate)
      .def("estimated_nodes", &WeaveParams::estimatedNodes, "nodes the weave will have (upper bound)");
  bp::scope().attr("MAX_WEAVE_NODES") = kMaxWeaveNodes;
  bp::def("penalty_dt_limit", &penaltyDtLimit, (bp::arg("m"), bp::arg("k")),
          "Largest stable time step [s] of a penalty contact of effective mass m [kg] > 0 and stiffness k [N/m] > 0: "
          "2 sqrt(m / k).");
  bp::def("km2_706", &km2_706, "KM2 style 706 preset parameters.");
  bp::def("cylinder_min_along", +[](Real radius, Real halfLength, Real chiselAngle, Real landHalfWidth, const Vec3& n) {
            RigidPart p;
            p.type = RigidPart::Type::Cylinder, p.radius = radius, p.halfLength = halfLength;
            p.chiselAngle = chiselAngle, p.landHalfWidth = landHalfWidth;
            require(std::isfinite(radius) && radius >= 1e-9 && radius <= 10, "radius", radius, "[1e-9, 10] m");
            validateCylinder(p);
            require(n.allFinite() && std::abs(n.norm() - 1) < 1e-9, "n", n.norm(), "a unit vector");
            return cylinderMinAlong(p, n);
          },
          (bp::arg("radius"), bp::arg("half_length"), bp::arg("chisel_angle"), bp::arg("land_half_width"), bp::arg("n")),
          "min over a cylinder part (axis z, centre at the origin; chisel nose at +z: shape/Cylinder.hpp) of y.n [m], "
          "n a unit vector in its frame: exact.");
  bp::def("set_threads", +[](int n) {
            require(n >= 0 && n <= 1024, "threads", n, "[0, 1024] (0: follow OpenMP: OMP_NUM_THREADS, yade -j N)");
            setThreads(n);
          },
          (bp::arg("n")),
          "Threads of woven's loops in every engine: n >= 1 forces n, 0 follows OpenMP (OMP_NUM_THREADS, YADE's "
          "-j N). Results are the same bits at any count (docs/design.md, Threads).");
  bp::def("threads", +[]() { return threads(); }, "Threads woven's loops use now (in the calling thread).");
  bp::def("release_threads", +[]() { return releaseThreads(); },
          "Ends the calling thread's idle OpenMP team (woven.attach does it: the script's thread hands the "
          "stepping to YADE's loop thread). While a team idles in another thread, libgomp makes every team's "
          "threads sleep at each barrier, and two threads gain little (docs/design.md, Threads). True when done.");
  bp::def("ideal_loop_seconds", +[](int n, int rounds) {
            require(n >= 1 && n <= 1024, "threads", n, "[1, 1024]");
            require(rounds >= 1 && rounds <= 100000, "rounds", rounds, "[1, 100000]");
            return idealLoopSeconds(n, rounds);
          },
          (bp::arg("threads"), bp::arg("rounds") = 200),
          "Wall time [s] of an ideal parallel loop (independent arithmetic, no serial part) on `threads` "
          "threads, `rounds` regions: what the cores give, for the benchmarks' speed-ups (core/ThreadCeiling.hpp).");
  bp::def("openmp_threads", +[]() { return openmpThreads(); },
          "OpenMP's count in the calling thread (omp_get_max_threads; 1 without OpenMP).");

  bp::class_<WeaveSummary>("WeaveSummary", "Measured figures of a built weave (SI).")
      .def_readonly("warp_yarns", &WeaveSummary::warpYarns).def_readonly("weft_yarns", &WeaveSummary::weftYarns)
      .def_readonly("nodes", &WeaveSummary::nodes).def_readonly("elements", &WeaveSummary::elements)
      .def_readonly("spans", &WeaveSummary::spans).def_readonly("fine_spans", &WeaveSummary::fineSpans)
      .def_readonly("min_element_length", &WeaveSummary::minElementLength, "[m]")
      .def_readonly("warp_peirce", &WeaveSummary::warpPeirce).def_readonly("weft_peirce", &WeaveSummary::weftPeirce)
      .def_readonly("warp_crimp_built", &WeaveSummary::warpCrimpBuilt)
      .def_readonly("weft_crimp_built", &WeaveSummary::weftCrimpBuilt)
      .def_readonly("areal_density", &WeaveSummary::arealDensity, "[kg/m^2]")
      .def_readonly("required_gap", &WeaveSummary::requiredGap, "[m]")
      .def_readonly("min_vertical_gap", &WeaveSummary::minVerticalGap, "[m]")
      .def_readonly("min_chain_clearance", &WeaveSummary::minChainClearance, "[m]")
      .def_readonly("length_x", &WeaveSummary::lengthX).def_readonly("length_y", &WeaveSummary::lengthY);
  bp::def("build_weave", &buildWeavePy, (bp::arg("params")),
          "Builds a weave: returns (FabricEngine, WeaveSummary, warp yarn indices, weft yarn indices).");

  bp::class_<Fabric>("Fabric", "A set of yarns to simulate; add yarns, then make a FabricEngine.")
      .def("add_yarn", &addYarn, (bp::arg("points"), bp::arg("material"), bp::arg("section")),
           "Appends a yarn through the node positions [m] (Vector3 list); returns its index.")
      .add_property("n_nodes", &Fabric::nNodes).add_property("n_elements", &Fabric::nElems)
      .add_property("n_yarns", &Fabric::nYarns);

  bp::register_ptr_to_python<std::shared_ptr<FabricEngine>>();
  bp::class_<FabricEngine, boost::noncopyable>("FabricEngine", "The fabric and its step (SI).", bp::no_init)
      .def("__init__", bp::make_constructor(&makeEngine))
      .add_property("n_nodes", +[](FabricEngine& e) { return e.fabric().nNodes(); })
      .add_property("n_elements", +[](FabricEngine& e) { return e.fabric().nElems(); })
      .add_property("n_yarns", +[](FabricEngine& e) { return e.fabric().nYarns(); })
      .add_property("dt_crit", &FabricEngine::criticalDt, "critical time step of the chain [s]")
      .add_property("dt_max", &FabricEngine::maxStep, "longest step accepted [s]: substeps x dt_crit")
      .add_property("substeps", &FabricEngine::substeps, &FabricEngine::setSubsteps,
                    "spring substeps per step, [1, 64]: the springs step at dt / substeps, the collisions once per step "
                    "(multiple time stepping; only without penalty response or section springs)")
      .add_property("multirate", &FabricEngine::multiRate, &FabricEngine::setMultiRate,
                    "multi-rate springs with substeps > 1: the elements stable at dt_max step once per step (r-RESPA's "
                    "slow force), the others substeps times; later substeps solve again only the rows near a fast node or a body")
      .add_property("time", +[](FabricEngine& e) { return e.dynamics().time(); }, "simulated time [s]")
      .add_property("iter", +[](FabricEngine& e) { return e.dynamics().stepCount(); }, "steps taken")
      .add_property("blowup_factor", &blowup, &setBlowup)
      .add_property("checkpoint_interval", &checkpointInterval, &setCheckpointInterval)
      .add_property("gravity", &getGravity, &gravity, "body acceleration [m/s^2]")
      .def("step", &FabricEngine::step, (bp::arg("dt")), "One step of dt [s] (refused above dt_max).")
      .def("run", &runSteps, (bp::arg("dt"), bp::arg("steps")), "steps steps of dt [s], in C++.")
      .def("pos", &nodePos, (bp::arg("node")), "position [m]")
      .def("vel", &nodeVel, (bp::arg("node")), "velocity at the current step [m/s]")
      .def("set_pos", &setNodePos, (bp::arg("node"), bp::arg("position")))
      .def("set_vel", &setNodeVel, (bp::arg("node"), bp::arg("velocity")))
      .def("mass", &nodeMass, (bp::arg("node")), "lumped node mass [kg]")
      .def("element_nodes", &elementNodes, (bp::arg("element")))
      .def("yarn", &yarnInfo, (bp::arg("yarn")))
      .def("fix", &fixNode, (bp::arg("node")))
      .def("prescribe_velocity", &prescribe, (bp::arg("node"), bp::arg("velocity")), "[m/s]")
      .def("release", &releaseNode, (bp::arg("node")))
      .def("is_kinematic", &isKinematic, (bp::arg("node")))
      .def("set_point_force", &pointForce, (bp::arg("node"), bp::arg("force")), "[N]")
      .def("reaction", &reactionOf, (bp::arg("nodes")), "support force on these kinematic nodes [N]")
      .def("energy", &energyDict, "kinetic, elastic, damped, work, initial, contact (taken by the contact stage), contact_input, balance_error [J]")
      .def("_positions", +[](FabricEngine& e) { return bytesOf(e.fabric().pos); })
      .def("_velocities", &syncVelocities)
      .def("_strains", +[](FabricEngine& e) { e.dynamics().refreshForces(); return bytesOf(e.fabric().strain); })
      .def("_tensions", +[](FabricEngine& e) { e.dynamics().refreshForces(); return bytesOf(e.fabric().tension); })
      .def("_masses", +[](FabricEngine& e) { return bytesOf(e.fabric().mass); })
      .def("_rest_lengths", +[](FabricEngine& e) { return bytesOf(e.fabric().restLength); })
      .def("_element_first_nodes", +[](FabricEngine& e) { return bytesOf(e.fabric().elem0); })
      .def("save_state", &saveStatePy, (bp::arg("path"), bp::arg("last_good") = false),
           "Writes positions, velocities, sections and the clock, bit for bit (last_good: the last state "
           "that passed the checks).")
      .def("load_state", &loadStatePy, (bp::arg("path")))
      .def("restore_last_good", +[](FabricEngine& e) {
        e.dynamics().restoreLastGood();
        if (e.collisions()) e.collisions()->invalidateCache();
      })
      .add_property("velocity_ramp", +[](FabricEngine& e) { return e.dynamics().loads().velocityRamp; },
                    +[](FabricEngine& e, Real t) { e.dynamics().setVelocityRamp(t); },
                    "prescribed velocities grow linearly over this time from t = 0 [s] (0: at once)")
      .def("enable_collisions", &enableCollisionsPy,
           (bp::arg("restitution") = 0.0, bp::arg("friction") = 0.0, bp::arg("body_friction") = 0.0, bp::arg("mcd") = 0.6,
            bp::arg("section_rule") = "constant_area", bp::arg("margin") = 1e-6, bp::arg("tolerance") = 1e-6,
            bp::arg("max_iterations") = 50, bp::arg("flatten_passes") = 4, bp::arg("position_correction") = 0.2,
            bp::arg("correction_slop") = 0.5e-6, bp::arg("self_exclude") = 1, bp::arg("broad_phase") = "tree",
            bp::arg("skin") = 5e-6, bp::arg("threads") = 0, bp::arg("yarn_contacts") = true, bp::arg("contact_cache") = 1e-7,
            bp::arg("response") = "impulse", bp::arg("penalty_stiffness") = 1e5, bp::arg("penalty_damping") = 0.0,
            bp::arg("flattening") = "geometric", bp::arg("section_stiffness") = 1e4, bp::arg("contact_model") = "gap",
            bp::arg("projection_sweeps") = -1, bp::arg("projection_slop") = 0.5e-6, bp::arg("projection_max_move") = 10e-6,
            bp::arg("sweep_order") = "sequential", bp::arg("projection_check") = 2e-6, bp::arg("crossings") = "persistent",
            bp::arg("solver_tolerance") = 1e-9),
           "Collision handling (paper Sec. 4-5), SI: restitution e in [0, 1], Coulomb friction (yarn-yarn) and body_friction "
           "(rigid body-yarn) in [0, 2], 0 with response 'penalty', mcd in (0, 1), "
           "section_rule 'constant_area' or 'paper', margin [m] >= 0, tolerance [m/s] > 0, position_correction "
           "in [0, 1] per step, correction_slop [m], broad_phase 'tree', 'grid' or 'sap', skin [m] >= 0 (Verlet skin of "
           "the broad phase), threads in [0, 64] (collision stage; 0: woven.threads(); same results for any count), yarn_contacts (False: only "
           "contacts with rigid bodies), contact_cache [m] >= 0 (a contact is carried while its nodes move "
           "together to within this; 0: off), response 'impulse' or 'penalty', penalty_stiffness k_p [N/m] > 0, "
           "penalty_damping zeta in [0, 1), flattening 'geometric', 'none' or 'springs', section_stiffness k_s [N/m] > 0 "
           "(docs/collisions.md), contact_model 'gap' (gap functions, exact gradient rows, position projection) or "
           "'paper' (Sections 4-5), projection_sweeps in [0, 50] or -1 (auto: 8 with 'gap' and 'impulse', else 0), "
           "projection_slop [m] in [0, 1e-3], projection_max_move [m] in (0, 1e-3], sweep_order 'sequential' (contact order; the default), "
           "'coloured' (rows of a colour on the threads) or 'blocked' (slabs of the ply on the threads), projection_check [m] in [0, 1e-3] or -1 (contacts still deeper "
           "after the flattening are projected out before the rows; -1: no check), crossings 'persistent' (one contact per crossing, "
           "carried between steps; the default) or 'chords' (every CP pair measured afresh), solver_tolerance [m] in [0, 1e-3] "
           "(the impulse sweeps stop once no row errs the step's drift by more; 0: tolerance alone). See woven.contact.")
      .def("disable_collisions", +[](FabricEngine& e) { e.disableCollisions(); })
      .add_property("collisions_enabled", +[](FabricEngine& e) { return e.collisions() != nullptr; })
      .def("settle_sections", +[](FabricEngine& e, int passes) { return stageOf(e).settle(e.fabric(), passes); },
           (bp::arg("max_passes") = 100),
           "Flattens the sections where yarns overlap, moving nothing; returns the overlap left [m].")
      .def("overlap", +[](FabricEngine& e) { return stageOf(e).overlap(e.fabric()); },
           "Largest overlap between CPs in the current state [m].")
      .def("collision_stats", &collisionStats, "dict: last step's counts, and maxima since the start (SI)")
      .def("_candidate_pairs", &candidatePairsPy, (bp::arg("broad_phase")))
      .def("_contacts", &contactsPy)
      .def("_crossings", &crossingsPy)
      .def("enable_breakage", &enableBreakage,
           (bp::arg("strain") = 0.0, bp::arg("filter_length") = -4.0, bp::arg("weibull_m") = 0.0, bp::arg("seed") = 1),
           "Yarn breakage: an element breaks when its strain, low-pass filtered in time over tau = "
           "L / c (L = filter_length [m] when > 0, |filter_length| element lengths when < 0 (default 4), 0: raw "
           "element strain), passes the failure strain (strain <= 0: each "
           "yarn's material failure_strain; else in (0, 10]). weibull_m in [1, 100] draws each yarn's strength "
           "from a Weibull law of that modulus with the failure strain as mean (seed >= 0); 0: no scatter.")
      .def("disable_breakage", +[](FabricEngine& e) { e.dynamics().configureBreakage(BreakageParams{}); })
      .add_property("breakage_enabled", +[](FabricEngine& e) { return e.dynamics().breakage().enabled(); })
      .def("break_log", &breakLog, "list of dicts: step, time [s], yarn, element, position [m], strain (filtered) "
           "and raw_strain [-], energy released [J]")
      .add_property("broken_elements", +[](FabricEngine& e) { return e.dynamics().breakage().brokenElements(); })
      .add_property("broken_yarns", +[](FabricEngine& e) { return e.dynamics().breakage().brokenYarns(e.fabric()); })
      .def("_filtered_strains", +[](FabricEngine& e) { return bytesOf(e.dynamics().breakage().filteredStrain()); })
      .def("_yarn_strengths", +[](FabricEngine& e) { return bytesOf(e.dynamics().breakage().yarnStrength()); })
      .def("_alive", +[](FabricEngine& e) { return bytesOf(e.fabric().alive); })
      .def("add_body", &addBody,
           (bp::arg("id"), bp::arg("parts"), bp::arg("mass"), bp::arg("inertia"), bp::arg("pos"), bp::arg("ori"),
            bp::arg("vel"), bp::arg("ang_vel")),
           "Adds a rigid body the fabric collides with (needs collisions on): YADE body id, parts [('box', "
           "half_extents [m], offset [m], Quaternion), ('sphere', radius [m], offset, Quaternion), ('cylinder', "
           "(radius, half_length, chisel_angle, land_half_width), offset, Quaternion), ('triangle', (v0, v1, v2), "
           "offset, Quaternion) (a closed mesh's face, counter-clockwise from outside) or ('facet', (v0, v1, v2), "
           "offset, Quaternion) (a lone facet, both faces outside)] in the body frame, mass [kg] (0 or inf: kinematic), principal inertia [kg m^2], pos [m], ori, vel [m/s], "
           "ang_vel [rad/s]. Returns its index.")
      .add_property("n_bodies", +[](FabricEngine& e) { return e.collisions() ? static_cast<int>(e.collisions()->bodies.size()) : 0; })
      .def("body", &bodyDict, (bp::arg("index")),
           "dict: id, mass, inertia, pos, ori, vel, ang_vel, kinetic_energy [J], parts, friction (negative: body_friction)")
      .def("set_body_friction", &setBodyFriction, (bp::arg("index"), bp::arg("mu")),
           "body `index`'s own Coulomb coefficient with the yarns, [0, 2] (negative: the law's body_friction)")
      .def("set_body_state", &setBodyState, (bp::arg("index"), bp::arg("pos"), bp::arg("ori"), bp::arg("vel"), bp::arg("ang_vel")),
           "State at the start of the next step (SI).")
      .def("body_overlap", +[](FabricEngine& e, int k) { bodyAt(e, k); return bodyStage(e).bodyOverlap(e.fabric(), k); },
           (bp::arg("index")), "largest overlap of the body with a yarn as things stand [m] (<= 0: clear)")
      .def("pop_body", +[](FabricEngine& e) { if (e.collisions() && !e.collisions()->bodies.empty()) e.collisions()->bodies.pop_back(); })
      .def("_body_parts", +[](FabricEngine& e, int k) {  // [(kind, half extents | radius, centre, axes rows)]
        const RigidBody& b = bodyAt(e, k);
        bp::list out;
        for (std::size_t i = 0; i < b.parts.size(); ++i) {
          const Mat3 A = b.partAxes(i);
          bp::list rows;
          for (int r = 0; r < 3; ++r) rows.append(bp::make_tuple(A(r, 0), A(r, 1), A(r, 2)));
          const RigidPart& q = b.parts[i];
          if (q.type == RigidPart::Type::Cylinder)
            out.append(bp::make_tuple("cylinder", bp::make_tuple(q.radius, q.halfLength, q.chiselAngle, q.landHalfWidth),
                                      b.partCentre(i), rows));
          else if (q.type == RigidPart::Type::Triangle)
            out.append(bp::make_tuple(q.twoSided ? "facet" : "triangle",
                                      bp::make_tuple(b.partVertex(i, 0), b.partVertex(i, 1), b.partVertex(i, 2)),
                                      b.partCentre(i), rows));
          else if (q.type == RigidPart::Type::Box) out.append(bp::make_tuple("box", b.parts[i].halfSize, b.partCentre(i), rows));
          else out.append(bp::make_tuple("sphere", b.parts[i].radius, b.partCentre(i), rows));
        }
        return out;
      })
      .def("clear_bodies", +[](FabricEngine& e) { if (e.collisions()) e.collisions()->bodies.clear(); })
      .def("_yade_step", &yadeStep, (bp::arg("dt"), bp::arg("bodies"), bp::arg("rewind")))
      .def("_body_contacts", +[](FabricEngine& e) {  // cp, body, part, gap [m], normal x y z, point x y z, s, time [s]
        std::vector<Real> out;
        for (const BodyContact& c : stageOf(e).bodyContacts())
          out.insert(out.end(), {Real(c.cp), Real(c.body), Real(c.part), c.gap, c.normal.x(), c.normal.y(), c.normal.z(),
                                 c.point.x(), c.point.y(), c.point.z(), c.s, c.time});
        return bytesOf(out);
      })
      .def("_section_dirs", +[](FabricEngine& e) { return bytesOf(e.fabric().secDir); })
      .def("_section_flattening", +[](FabricEngine& e) { return bytesOf(e.fabric().secFlat); })
      .def("_section_semi_axes", &semiAxesPy)
      // The whole engine as bytes (pkg/engine/Snapshot.hpp; the native YADE plugin's O.save format);
      // the collision stage's memory with it, as save_state: taking one changes nothing.
      .def("_same", +[](FabricEngine& a, FabricEngine& b) { return &a == &b; }, (bp::arg("other")))
      .def("_snapshot", +[](FabricEngine& e) {
        const std::string b = engineSnapshot(e);
        return bp::object(bp::handle<>(PyBytes_FromStringAndSize(b.data(), static_cast<Py_ssize_t>(b.size()))));
      });
  // The build this module belongs to (a literal compiled here, so no other library can stand in for
  // it): the native YADE plugin's engine steps objects of this module only when its core library
  // reports the same id (py/woven/_native.py, pkg/engine/HostBridge.hpp).
#ifdef WOVEN_BUILD_ID
  bp::def("_build_id", +[]() { return std::string(WOVEN_BUILD_ID); });
#else
  bp::def("_build_id", +[]() { return std::string("default"); });
#endif
  bp::def("_engine_from_snapshot", +[](bp::object bytes) {
    char* data = nullptr;
    Py_ssize_t n = 0;
    if (PyBytes_AsStringAndSize(bytes.ptr(), &data, &n) != 0) bp::throw_error_already_set();
    return restoreSnapshot(std::string(data, static_cast<std::size_t>(n)));
  }, (bp::arg("snapshot")), "A FabricEngine rebuilt from FabricEngine._snapshot() bytes, continuing bit for bit.");
}
