// Engine snapshots (pkg/engine/Snapshot.hpp, what the YADE plugin stores in O.save's files): an
// engine rebuilt from the bytes continues bit for bit as the engine that wrote them, with collisions,
// a rigid body, loads and yarn breaks; damaged bytes are refused.
#include "body_util.hpp"
#include "chain_util.hpp"
#include "engine/Snapshot.hpp"
#include "same_bits.hpp"
#include "weave/WeaveBuilder.hpp"
#include <gtest/gtest.h>
#include <cstring>

using namespace woven;
using namespace woven_test;

namespace {

// A 16 x 16-yarn ply, one CP per crossing, ends clamped, a gravity and a point force, breakage at
// 1 % raw strain, a cube at 600 m/s onto its middle: contacts and breaks within a few hundred steps.
std::shared_ptr<FabricEngine> struckPly() {
  WeaveParams p = km2_706();
  p.nx = p.ny = 8;
  p.cpPerSpan = 1;
  auto e = std::make_shared<FabricEngine>(buildWeave(p).fabric);
  ContactParams c;
  c.skin = 1e-5;
  e->enableCollisions(c, BroadPhase::Grid);
  for (const Yarn& y : e->fabric().yarns) e->dynamics().fix(y.firstNode), e->dynamics().fix(y.firstNode + y.nNodes - 1);
  e->dynamics().setBodyAcceleration(Vec3(0, 0, -9.81));
  e->dynamics().setPointForce(5, Vec3(0, 0, 1e-3));
  BreakageParams b;
  b.enabled = true, b.threshold = 0.01, b.filterLength = 0;
  e->dynamics().configureBreakage(b);
  RigidBody spinning = cubeAbove(e->fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -600));
  spinning.angVel = Vec3(0, 2e3, 0);
  e->collisions()->bodies.push_back(spinning);
  return e;
}


}  // namespace

TEST(Snapshot, RestoredEngineContinuesBitForBit) {
  auto a = struckPly();
  const Real dt = 0.7 * a->criticalDt();
  for (int s = 0; s < 150; ++s) a->step(dt);
  const std::string bytes = engineSnapshot(*a);
  auto b = restoreSnapshot(bytes);
  EXPECT_EQ(b->criticalDt(), a->criticalDt());
  for (int s = 0; s < 250; ++s) a->step(dt), b->step(dt);
  // The scene did what the test needs: the cube touched the ply and yarns broke after the snapshot.
  EXPECT_GT(a->collisions()->stats.bodyContacts + a->dynamics().breakage().brokenElements(), 0);
  EXPECT_GT(a->dynamics().breakage().brokenElements(), 0);
  expectSameRun(*a, *b);
  // A snapshot of the restored engine restores the same again.
  auto c = restoreSnapshot(engineSnapshot(*b));
  engineSnapshot(*a);
  for (int s = 0; s < 20; ++s) a->step(dt), c->step(dt);
  expectSameRun(*a, *c);
}

// Spring substeps are part of the engine's settings: the restored engine takes the same long
// steps and continues bit for bit (format WOVENSN4 writes the substeps and the multi-rate flag
// always: the bytes' size does not change with them).
TEST(Snapshot, SubstepsRoundTrip) {
  auto a = struckPly();
  const std::size_t plain = engineSnapshot(*a).size();
  a->setSubsteps(3);
  EXPECT_EQ(engineSnapshot(*a).size(), plain);
  const Real dt = 3 * 0.7 * a->criticalDt();
  for (int s = 0; s < 50; ++s) a->step(dt);
  const std::string bytes = engineSnapshot(*a);
  auto b = restoreSnapshot(bytes);
  EXPECT_EQ(b->substeps(), 3);
  for (int s = 0; s < 60; ++s) a->step(dt), b->step(dt);
  EXPECT_GT(a->collisions()->stats.bodyContacts + a->dynamics().breakage().brokenElements(), 0);
  expectSameRun(*a, *b);
}

// Multi-rate springs too: an adaptive ply (4 CPs per span near the cube, 1 elsewhere) at 4 substeps,
// its coarse CPs once per step; the restored engine chooses the same slow elements and continues
// bit for bit. The flag is one byte after the substeps.
TEST(Snapshot, MultiRateRoundTrip) {
  WeaveParams w = km2_706();
  w.nx = w.ny = 8;
  w.cpPerSpan = 4, w.cpCoarse = 1, w.fineRadius = 1.5e-3;
  auto a = std::make_shared<FabricEngine>(buildWeave(w).fabric);
  ContactParams c;
  c.skin = 1e-5;
  a->enableCollisions(c, BroadPhase::Grid);
  for (const Yarn& y : a->fabric().yarns) a->dynamics().fix(y.firstNode), a->dynamics().fix(y.firstNode + y.nNodes - 1);
  a->collisions()->bodies.push_back(cubeAbove(a->fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -600)));
  a->setSubsteps(4);
  const std::size_t single = engineSnapshot(*a).size();
  a->setMultiRate(true);
  EXPECT_EQ(engineSnapshot(*a).size(), single);
  const Real dt = 4 * 0.7 * a->criticalDt();
  for (int s = 0; s < 40; ++s) a->step(dt);
  long slow = 0;
  for (std::uint8_t x : a->dynamics().slowElementMask()) slow += x;
  EXPECT_GT(slow, 0) << "the coarse CPs are slow";
  auto b = restoreSnapshot(engineSnapshot(*a));
  EXPECT_TRUE(b->multiRate());
  for (int s = 0; s < 60; ++s) a->step(dt), b->step(dt);
  EXPECT_GT(a->collisions()->stats.bodyContacts, 0);
  EXPECT_EQ(a->dynamics().slowElementMask(), b->dynamics().slowElementMask());
  expectSameRun(*a, *b);
}

TEST(Snapshot, DamagedBytesAreRefused) {
  auto a = struckPly();
  std::string bytes = engineSnapshot(*a);
  EXPECT_EQ(parameterOf([&] { restoreSnapshot(bytes.substr(0, bytes.size() - 1)); }), "snapshot");
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 1;
  EXPECT_EQ(parameterOf([&] { restoreSnapshot(flipped); }), "snapshot");
  EXPECT_EQ(parameterOf([&] { restoreSnapshot("WOVENST3"); }), "snapshot");
  EXPECT_NO_THROW(restoreSnapshot(bytes));
}

// A cylinder part (the FSP's chisel-nosed one) keeps its dimensions through the bytes, and the
// restored engine continues the impact bit for bit.
TEST(Snapshot, CylinderPartRoundTrips) {
  auto a = struckPly();
  RigidBody& b = a->collisions()->bodies[0];
  RigidPart& part = b.parts[0];
  part.type = RigidPart::Type::Cylinder;
  part.radius = 1.4e-3, part.halfLength = 1.6e-3, part.chiselAngle = 0.61, part.landHalfWidth = 0.47e-3;
  b.ori = Quat(Eigen::AngleAxis<Real>(M_PI, Vec3::UnitX()));  // nose down
  b.validate();
  const Real dt = 0.7 * a->criticalDt();
  for (int s = 0; s < 100; ++s) a->step(dt);
  auto c = restoreSnapshot(engineSnapshot(*a));
  const RigidPart& q = c->collisions()->bodies[0].parts[0];
  EXPECT_EQ(q.type, RigidPart::Type::Cylinder);
  EXPECT_EQ(q.radius, part.radius);
  EXPECT_EQ(q.halfLength, part.halfLength);
  EXPECT_EQ(q.chiselAngle, part.chiselAngle);
  EXPECT_EQ(q.landHalfWidth, part.landHalfWidth);
  for (int s = 0; s < 150; ++s) a->step(dt), c->step(dt);
  EXPECT_GT(a->collisions()->stats.bodyContacts + a->dynamics().breakage().brokenElements(), 0);
  expectSameRun(*a, *c);
}
