// A straight yarn with collisions on, for the rigid-body tests (test_ballistic, test_substeps): its
// round section, the engine, and the total momentum of the fabric and its bodies.
#pragma once
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include <memory>

namespace woven_test {

inline woven::YarnSection roundSection(woven::Real r) {
  woven::YarnSection s;
  s.width = s.thickness = 2 * r;
  return s;
}

/// A straight round yarn (r = 0.1 mm) of 40 CPs of 0.25 mm along x at z = 0, at rest, with
/// collisions on (restitution e, no positional correction), its ends clamped or free.
inline std::unique_ptr<woven::FabricEngine> yarnEngine(woven::Real restitution, bool clampEnds) {
  woven::Vec3Array pts;
  for (int i = 0; i <= 40; ++i) pts.push_back(woven::Vec3((i - 20) * 0.25e-3, 0, 0));
  woven::Fabric f;
  f.addYarn(pts, km2Material(), roundSection(1e-4));
  auto e = std::make_unique<woven::FabricEngine>(std::move(f));
  if (clampEnds) e->dynamics().fix(0), e->dynamics().fix(40);
  woven::ContactParams p;
  p.restitution = restitution;
  p.positionCorrection = 0;
  e->enableCollisions(p);
  return e;
}

/// Total momentum of the nodes and the collision stage's bodies [kg m/s].
inline woven::Vec3 momentum(const woven::FabricEngine& e) {
  woven::Vec3 p = woven::Vec3::Zero();
  for (woven::Index i = 0; i < e.fabric().nNodes(); ++i) p += e.fabric().mass[i] * e.fabric().vel[i];
  for (const woven::RigidBody& b : e.collisions()->bodies) p += b.mass * b.vel;
  return p;
}

}  // namespace woven_test
