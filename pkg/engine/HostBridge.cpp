#include "engine/HostBridge.hpp"
#include "engine/FabricEngine.hpp"
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

}  // namespace woven
