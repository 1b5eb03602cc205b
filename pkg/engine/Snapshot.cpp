#include "engine/Snapshot.hpp"
#include "core/ByteStream.hpp"
#include "core/Errors.hpp"
#include <cmath>
#include <cstring>

namespace woven {

namespace {

// WOVENSN4 (this build's): the collision stage's memory after the breaks, the substeps and the
// multi-rate flag always, the yarns' rest turns (bending), their materials with the bending
// stiffness, each body's own friction. Earlier formats laid the fabric, its materials and bodies
// out otherwise: refused.
constexpr char kMagic[8] = {'W', 'O', 'V', 'E', 'N', 'S', 'N', '4'};

std::uint64_t fnv64(const char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(p[i])) * 1099511628211ull;
  return h;
}

[[noreturn]] void snapshotFails(const std::string& what) {
  throw ParameterError("snapshot", what, "bytes written by woven::engineSnapshot of this build (format WOVENSN4)");
}

// Plain structs go as their bytes (trivially copyable, same build): checked at compile time.
static_assert(std::is_trivially_copyable<Yarn>::value && std::is_trivially_copyable<YarnMaterial>::value &&
                  std::is_trivially_copyable<ContactParams>::value &&
                  std::is_trivially_copyable<BreakageParams>::value && std::is_trivially_copyable<EnergyBooks>::value &&
                  std::is_trivially_copyable<InstabilityLimits>::value,
              "snapshot: a plain struct is no longer trivially copyable");

void putBreakEvents(ByteWriter& o, const std::vector<BreakEvent>& log) {
  o.put(static_cast<std::uint64_t>(log.size()));
  for (const BreakEvent& ev : log) {
    o.put(static_cast<std::int64_t>(ev.step)), o.put(ev.time), o.put(ev.yarn), o.put(ev.element);
    o.put(ev.position), o.put(ev.strain), o.put(ev.rawStrain), o.put(ev.energy);
  }
}

void getBreakEvents(ByteReader& in, std::vector<BreakEvent>& log) {
  log.resize(in.count(1));
  for (BreakEvent& ev : log) {
    ev.step = static_cast<long>(in.get<std::int64_t>()), ev.time = in.get<Real>(), ev.yarn = in.get<Index>();
    ev.element = in.get<Index>(), ev.position = in.get<Vec3>(), ev.strain = in.get<Real>();
    ev.rawStrain = in.get<Real>(), ev.energy = in.get<Real>();
  }
}

}  // namespace

std::string engineSnapshot(FabricEngine& e) {
  const Fabric& f = e.fabric();
  const ChainDynamics& d = e.dynamics();
  ByteWriter o;
  o.b.append(kMagic, 8);
  // Fabric: every array (forces, strains and tensions are recomputed on restore).
  o.vec(f.pos), o.vec(f.vel), o.vec(f.mass), o.vec(f.invMass), o.vec(f.nodeYarn);
  o.vec(f.secRadius), o.vec(f.secFlat), o.vec(f.secDir);
  o.vec(f.elem0), o.vec(f.restLength), o.vec(f.stiffness), o.vec(f.damping), o.vec(f.alive), o.vec(f.elemYarn);
  o.vec(f.restTurn);
  o.vec(f.yarns), o.vec(f.materials);
  // Loads and limits.
  const Loads& L = d.loads();
  o.put(L.bodyAcceleration), o.vec(L.kinematicNodes), o.vec(L.kinematicVelocity), o.put(L.velocityRamp);
  o.vec(L.forceNodes), o.vec(L.forceValues);
  o.put(d.limits);
  // Collision stage: settings and bodies.
  const CollisionStage* st = e.collisions();
  o.put(std::uint8_t(st != nullptr));
  if (st) {
    o.put(st->params()), o.put(st->broadPhase), o.put(st->bodyCollider.skin), o.put(st->tree.rebuildRatio);
    o.put(static_cast<std::uint64_t>(st->bodies.size()));
    for (const RigidBody& b : st->bodies) {
      o.put(static_cast<std::int64_t>(b.id)), o.put(static_cast<std::uint64_t>(b.parts.size()));
      for (const RigidPart& q : b.parts)
      {
        o.put(q.type), o.put(q.halfSize), o.put(q.radius), o.put(q.offset), o.put(q.ori.coeffs().eval());
        if (q.type == RigidPart::Type::Cylinder) o.put(q.halfLength), o.put(q.chiselAngle), o.put(q.landHalfWidth);
        if (q.type == RigidPart::Type::Triangle) o.put(q.vert[0]), o.put(q.vert[1]), o.put(q.vert[2]), o.put(std::uint8_t(q.twoSided));
      }
      o.put(b.mass), o.put(b.inertia), o.put(b.pos);
      o.put(b.ori.coeffs().eval()), o.put(b.vel), o.put(b.angVel), o.put(b.friction);
    }
  }
  // State (FabricEngine::state: what setState puts back).
  const KinematicState s = e.state();
  o.put(static_cast<std::int64_t>(s.step)), o.put(s.time), o.put(s.lastDt), o.put(s.topology);
  o.put(static_cast<std::int64_t>(s.yarns));
  o.put(std::uint8_t(s.booksStarted)), o.put(std::uint8_t(s.springSeen)), o.put(s.books);
  o.put(s.breakage.params), o.vec(s.breakage.strength), o.vec(s.breakage.filtered);
  putBreakEvents(o, s.breakage.log);
  o.put(static_cast<std::uint64_t>(s.contacts.size()));
  o.b.append(s.contacts);
  o.put(static_cast<std::int32_t>(e.substeps())), o.put(std::uint8_t(e.multiRate()));
  o.put(fnv64(o.b.data(), o.b.size()));
  return o.b;
}

std::shared_ptr<FabricEngine> restoreSnapshot(const std::string& bytes) {
  if (bytes.size() < 16 || std::memcmp(bytes.data(), kMagic, 8) != 0) snapshotFails("no WOVENSN4 header");
  std::uint64_t sum;
  std::memcpy(&sum, bytes.data() + bytes.size() - 8, 8);
  if (sum != fnv64(bytes.data(), bytes.size() - 8)) snapshotFails("checksum mismatch");
  const std::string body = bytes.substr(0, bytes.size() - 8);
  ByteReader in(body, 8, snapshotFails);
  Fabric f;
  in.vec(f.pos), in.vec(f.vel), in.vec(f.mass), in.vec(f.invMass), in.vec(f.nodeYarn);
  in.vec(f.secRadius), in.vec(f.secFlat), in.vec(f.secDir);
  in.vec(f.elem0), in.vec(f.restLength), in.vec(f.stiffness), in.vec(f.damping), in.vec(f.alive), in.vec(f.elemYarn);
  in.vec(f.restTurn);
  in.vec(f.yarns), in.vec(f.materials);
  const std::size_t n = f.pos.size(), ne = f.elem0.size();
  if (f.vel.size() != n || f.mass.size() != n || f.invMass.size() != n || f.nodeYarn.size() != n || f.restTurn.size() != n ||
      f.secRadius.size() != n || f.secFlat.size() != n || f.secDir.size() != n || f.restLength.size() != ne ||
      f.stiffness.size() != ne || f.damping.size() != ne || f.alive.size() != ne || f.elemYarn.size() != ne)
    in.fail("inconsistent array sizes");
  for (const Yarn& y : f.yarns)
    if (y.material < 0 || static_cast<std::size_t>(y.material) >= f.materials.size() || y.firstNode < 0 ||
        y.firstElem < 0 || static_cast<std::size_t>(y.firstNode) + y.nNodes > n ||
        static_cast<std::size_t>(y.firstElem) + y.nElems > ne)
      in.fail("a yarn outside the arrays");
  for (std::size_t e = 0; e < ne; ++e)
    if (f.elemYarn[e] < 0 || static_cast<std::size_t>(f.elemYarn[e]) >= f.yarns.size() || f.elem0[e] < 0 ||
        static_cast<std::size_t>(f.elem0[e]) + 1 >= n)
      in.fail("an element outside the arrays");
  KinematicState s;
  s.pos = f.pos, s.vel = f.vel, s.flat = f.secFlat, s.dir = f.secDir;
  s.alive = f.alive, s.stiffness = f.stiffness, s.damping = f.damping;
  // The elements as built (addYarn's formulas, as setState uses): the critical step is the one of
  // the built weave, as in the engine that wrote the snapshot; setState then puts the breaks back.
  f.strain.assign(ne, 0.0), f.tension.assign(ne, 0.0), f.force.assign(n, Vec3::Zero());
  for (std::size_t e = 0; e < ne; ++e) {
    const YarnMaterial& m = f.materials[f.yarns[f.elemYarn[e]].material];
    const Real K = m.E * m.area / f.restLength[e], me = m.rho * m.area * f.restLength[e];
    f.alive[e] = 1, f.stiffness[e] = K, f.damping[e] = m.dampingRatio * std::sqrt(K * me);
  }
  Loads L;
  L.bodyAcceleration = in.get<Vec3>(), in.vec(L.kinematicNodes), in.vec(L.kinematicVelocity);
  L.velocityRamp = in.get<Real>(), in.vec(L.forceNodes), in.vec(L.forceValues);
  if (L.kinematicVelocity.size() != L.kinematicNodes.size() || L.forceValues.size() != L.forceNodes.size())
    in.fail("inconsistent loads");
  const auto limits = in.get<InstabilityLimits>();
  auto e = std::make_shared<FabricEngine>(std::move(f));
  ChainDynamics& d = e->dynamics();
  d.limits = limits;
  for (std::size_t k = 0; k < L.kinematicNodes.size(); ++k) d.prescribeVelocity(L.kinematicNodes[k], L.kinematicVelocity[k]);
  d.setVelocityRamp(L.velocityRamp);
  d.setBodyAcceleration(L.bodyAcceleration);
  for (std::size_t k = 0; k < L.forceNodes.size(); ++k) d.setPointForce(L.forceNodes[k], L.forceValues[k]);
  if (in.get<std::uint8_t>()) {
    const auto p = in.get<ContactParams>();
    const auto broad = in.get<BroadPhase>();
    e->enableCollisions(p, broad);
    CollisionStage& st = *e->collisions();
    st.bodyCollider.skin = in.get<Real>(), st.tree.rebuildRatio = in.get<Real>();
    const auto nb = in.count(1);
    for (std::uint64_t k = 0; k < nb; ++k) {
      RigidBody b;
      b.id = static_cast<long>(in.get<std::int64_t>());
      b.parts.resize(in.count(1));
      for (RigidPart& q : b.parts) {
        q.type = in.get<RigidPart::Type>(), q.halfSize = in.get<Vec3>(), q.radius = in.get<Real>();
        q.offset = in.get<Vec3>(), q.ori.coeffs() = in.get<Eigen::Matrix<Real, 4, 1>>();
        if (q.type == RigidPart::Type::Cylinder)  // written only for cylinders: older snapshots have none
          q.halfLength = in.get<Real>(), q.chiselAngle = in.get<Real>(), q.landHalfWidth = in.get<Real>();
        if (q.type == RigidPart::Type::Triangle) {
          for (Vec3& v : q.vert) v = in.get<Vec3>();
          q.twoSided = in.get<std::uint8_t>() != 0;
        }
      }
      b.mass = in.get<Real>();
      b.inertia = in.get<Vec3>(), b.pos = in.get<Vec3>(), b.ori.coeffs() = in.get<Eigen::Matrix<Real, 4, 1>>();
      b.vel = in.get<Vec3>(), b.angVel = in.get<Vec3>(), b.friction = in.get<Real>();
      b.validate();
      st.bodies.push_back(b);
    }
  }
  s.step = static_cast<long>(in.get<std::int64_t>()), s.time = in.get<Real>(), s.lastDt = in.get<Real>();
  s.topology = in.get<std::uint64_t>(), s.yarns = static_cast<long>(in.get<std::int64_t>());
  s.booksStarted = in.get<std::uint8_t>() != 0, s.springSeen = in.get<std::uint8_t>() != 0;
  s.books = in.get<EnergyBooks>();
  s.breakage.params = in.get<BreakageParams>(), in.vec(s.breakage.strength), in.vec(s.breakage.filtered);
  getBreakEvents(in, s.breakage.log);
  int substeps = 1;
  bool multiRate = false;
  {
    const auto nc = static_cast<std::size_t>(in.count(1));
    s.contacts.assign(body.data() + in.at(), nc);
    in.skip(nc);
    substeps = in.get<std::int32_t>();
    if (substeps < 1 || substeps > 64) in.fail("substeps outside [1, 64]");
    const auto flag = in.get<std::uint8_t>();
    if (flag > 1) in.fail("multi-rate flag other than 0 or 1");
    multiRate = flag == 1;
  }
  if (in.left() != 0) in.fail("trailing bytes");
  if (substeps > 1) e->setSubsteps(substeps);
  e->setMultiRate(multiRate);  // before setState: it chooses the slow elements the state was saved with
  e->setState(s);  // checks everything (topology fingerprint, ranges) and puts clock, books, breaks back
  return e;
}

}  // namespace woven
