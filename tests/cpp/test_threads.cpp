// Threads change nothing (core/Parallel.hpp): the same scene stepped on 1, 2 and 3 threads ends in
// the same bits (positions, velocities, sections, broken elements, energy books, bodies). Scenes
// large enough that every parallel loop splits into several chunks: a decrimping weave with
// collisions, and a small clamped ply struck by a cube fast enough to break yarns.
#include "body_util.hpp"
#include "chain_util.hpp"
#include "core/Parallel.hpp"
#include "engine/FabricEngine.hpp"
#include "weave/WeaveBuilder.hpp"
#include <gtest/gtest.h>
#include <cstring>

using namespace woven;
using namespace woven_test;

namespace {

struct Outcome {
  Vec3Array pos, vel, dir;
  std::vector<Real> flat;
  std::vector<std::uint8_t> alive;
  EnergyBooks books;
  Vec3 bodyPos = Vec3::Zero(), bodyVel = Vec3::Zero();
  long contacts = 0, broken = 0;
};

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void expectSame(const Outcome& a, const Outcome& b, int threads) {
  EXPECT_TRUE(sameBits(a.pos, b.pos)) << threads << " threads: positions";
  EXPECT_TRUE(sameBits(a.vel, b.vel)) << threads << " threads: velocities";
  EXPECT_TRUE(sameBits(a.flat, b.flat)) << threads << " threads: section flattening";
  EXPECT_TRUE(sameBits(a.dir, b.dir)) << threads << " threads: section directions";
  EXPECT_TRUE(sameBits(a.alive, b.alive)) << threads << " threads: broken elements";
  EXPECT_EQ(std::memcmp(&a.books, &b.books, sizeof(EnergyBooks)), 0) << threads << " threads: energy books";
  EXPECT_EQ(std::memcmp(a.bodyPos.data(), b.bodyPos.data(), sizeof(Vec3)), 0) << threads << " threads: body position";
  EXPECT_EQ(std::memcmp(a.bodyVel.data(), b.bodyVel.data(), sizeof(Vec3)), 0) << threads << " threads: body velocity";
  EXPECT_EQ(a.contacts, b.contacts);
  EXPECT_EQ(a.broken, b.broken);
}

Outcome finish(FabricEngine& e) {
  Outcome o;
  const Fabric& f = e.fabric();
  o.pos = f.pos, o.vel = f.vel, o.dir = f.secDir, o.flat = f.secFlat, o.alive = f.alive;
  o.books = e.dynamics().energy();
  o.contacts = e.collisions()->stats.contacts;
  o.broken = e.dynamics().breakage().brokenElements();
  if (!e.collisions()->bodies.empty()) o.bodyPos = e.collisions()->bodies[0].pos, o.bodyVel = e.collisions()->bodies[0].vel;
  return o;
}

// 24 x 24 yarns of KM2 706 (~4600 CPs: several chunks of nodes, CPs and pairs), sections settled,
// warp ends pulled at 5 m/s with collisions on (tree broad phase, cache, flattening, impulses,
// positional correction).
Outcome tension(int threads, int steps) {
  setThreads(threads);
  WeaveParams p = km2_706();
  p.nx = p.ny = 12;
  p.warpMaterial.dampingRatio = p.weftMaterial.dampingRatio = 0.1;
  FabricEngine e(buildWeave(p).fabric);
  e.enableCollisions(ContactParams());
  e.collisions()->settle(e.fabric());
  for (const Yarn& y : e.fabric().yarns)
    if (y.family == YarnFamily::Warp) {
      e.dynamics().fix(y.firstNode);
      e.dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(5, 0, 0));
    }
  const Real dt = 0.7 * e.criticalDt();
  for (int s = 0; s < steps; ++s) e.step(dt);
  Outcome o = finish(e);
  setThreads(0);
  return o;
}

// A 40 x 40-yarn ply (one CP per crossing, ~3200 CPs, every yarn end clamped, grid broad phase) and
// a 3 mm, 1 g cube touching its middle at 1000 m/s; breakage at 1 % raw strain.
Outcome ballistic(int threads, int steps) {
  setThreads(threads);
  WeaveParams p = km2_706();
  p.nx = p.ny = 20;
  p.cpPerSpan = 1;
  FabricEngine e(buildWeave(p).fabric);
  ContactParams c;
  c.positionCorrection = 0, c.flattenPasses = 1, c.maxIterations = 10, c.skin = 1e-5;
  e.enableCollisions(c, BroadPhase::Grid);
  for (const Yarn& y : e.fabric().yarns) e.dynamics().fix(y.firstNode), e.dynamics().fix(y.firstNode + y.nNodes - 1);
  BreakageParams b;
  b.enabled = true, b.threshold = 0.01, b.filterLength = 0;
  e.dynamics().configureBreakage(b);
  e.collisions()->bodies.push_back(cubeAbove(e.fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -1000)));
  const Real dt = 0.7 * e.criticalDt();
  for (int s = 0; s < steps; ++s) e.step(dt);
  Outcome o = finish(e);
  setThreads(0);
  return o;
}

}  // namespace

TEST(Threads, TensionSceneIsTheSameBitsOnOneTwoAndThreeThreads) {
  const int steps = static_cast<int>(runLength(200, 4));
  const Outcome one = tension(1, steps);
  EXPECT_GT(one.contacts, 1000);
  for (int t : {2, 3}) expectSame(one, tension(t, steps), t);
}

TEST(Threads, BallisticSceneWithBreakageIsTheSameBitsOnOneTwoAndThreeThreads) {
  const int steps = static_cast<int>(runLength(300, 3));
  const Outcome one = ballistic(1, steps);
  EXPECT_GT(one.broken, 0) << "the cube breaks yarns within the run";
  EXPECT_GT(one.bodyVel.z(), -1000) << "the ply slows the cube";
  for (int t : {2, 3}) expectSame(one, ballistic(t, steps), t);
}

// The collision stage's own count (ContactParams::threads >= 1) overrides woven's for its loops only
// while it runs, and 0 follows woven's.
TEST(Threads, ContactThreadsForceTheStageCountOnly) {
  setThreads(1);
  EXPECT_EQ(threads(), 1);
  {
    const ThreadCountScope scope(3);
    EXPECT_EQ(threads(), 3);
    const ThreadCountScope none(0);
    EXPECT_EQ(threads(), 3);
  }
  EXPECT_EQ(threads(), 1);
  setThreads(0);
  EXPECT_EQ(threads(), openmpThreads());
  ContactParams p;
  EXPECT_EQ(p.threads, 0);
  p.threads = -1;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "threads");
  p.threads = 65;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "threads");
}
