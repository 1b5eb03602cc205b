// Reliability: refused input changes nothing, restarts are bit for bit with breakage and
// energy books, state files are checked whole before anything is loaded, writes are atomic and
// report errors, read-only queries move nothing, absurd physical values are refused.
#include "body_util.hpp"
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "fabric/StateIO.hpp"
#include "weave/WeaveBuilder.hpp"
#include "same_bits.hpp"
#include <gtest/gtest.h>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <dirent.h>
#include <fstream>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace woven;
using namespace woven_test;

namespace {

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "woven_rel_" + name + "_" + std::to_string(::getpid()) + ".state";
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A chain that has moved: arbitrary bits in positions and velocities.
std::unique_ptr<FabricEngine> movedChain(int elements = 32, Real l0 = 1e-3) {
  Fabric f = straightChain(elements, l0);
  randomVelocities(f, 5, 2.0);
  auto e = std::make_unique<FabricEngine>(std::move(f));
  const Real dt = 0.8 * e->criticalDt();
  for (int k = 0; k < 23; ++k) e->step(dt);
  return e;
}

}  // namespace

// --- defect 1: add_yarn is atomic ---

TEST(Reliability, RefusedYarnLeavesTheFabricAsItWas) {
  Fabric f = straightChain(4, 1e-3);
  const Index nodes = f.nNodes(), elems = f.nElems(), yarns = f.nYarns();
  const std::size_t mats = f.materials.size();
  Vec3Array pts = {Vec3(0, 1e-3, 0), Vec3(1e-3, 1e-3, 0), Vec3(NAN, 1e-3, 0), Vec3(3e-3, 1e-3, 0)};
  EXPECT_EQ(parameterOf([&] { f.addYarn(pts, km2Material(), YarnSection()); }), "points");
  pts[2] = Vec3(2e-3, 1e-3, 0), pts[3] = pts[2];  // a zero-length element, found after the points
  EXPECT_EQ(parameterOf([&] { f.addYarn(pts, km2Material(), YarnSection()); }), "points");
  EXPECT_EQ(f.nNodes(), nodes);
  EXPECT_EQ(f.nElems(), elems);
  EXPECT_EQ(f.nYarns(), yarns);
  EXPECT_EQ(f.materials.size(), mats);
  EXPECT_EQ(f.invMass.size(), f.mass.size());
  EXPECT_EQ(f.secDir.size(), f.pos.size());
  FabricEngine e(std::move(f));
  e.step(1e-9);  // used to read invMass past its end (segmentation fault)
  EXPECT_TRUE(e.fabric().pos[2].allFinite());
}

// --- defect 6: physical ranges ---

TEST(Reliability, AbsurdMaterialsAndPointsAreRefusedByName) {
  YarnMaterial m = km2Material();
  m.rho = 1e-300;
  EXPECT_EQ(parameterOf([&] { m.validate(); }), "rho");
  m = km2Material(), m.area = 1e300;
  EXPECT_EQ(parameterOf([&] { m.validate(); }), "area");
  m = km2Material(), m.E = 1e300;
  EXPECT_EQ(parameterOf([&] { m.validate(); }), "E");
  m = km2Material(), m.failureStrain = 1e300;
  EXPECT_EQ(parameterOf([&] { m.validate(); }), "failure_strain");
  YarnSection s;
  s.width = 1e300;
  EXPECT_EQ(parameterOf([&] { s.validate(); }), "width");
  Fabric f;
  EXPECT_EQ(parameterOf([&] { f.addYarn({Vec3(0, 0, 0), Vec3(1e200, 0, 0)}, km2Material(), YarnSection()); }), "points");
  EXPECT_EQ(f.nNodes(), 0);
  // Every accepted material gives a finite critical step and finite stiffness and damping.
  m = km2Material(), m.E = 1e13, m.rho = 1, m.area = 1e-2, m.dampingRatio = 9.9;
  f.addYarn({Vec3(0, 0, 0), Vec3(1e-9, 0, 0)}, m, YarnSection());
  EXPECT_TRUE(std::isfinite(criticalTimeStep(f)) && criticalTimeStep(f) > 0);
  EXPECT_TRUE(std::isfinite(f.stiffness[0]) && std::isfinite(f.damping[0]));
}

// --- defect 2: restart with breakage and energy books ---

namespace {

// A 12.7 mm single ply of KM2 706 (one CP per crossing, every yarn end clamped) struck in its middle
// by a 3 mm, 1 g cube at 300 m/s, with breakage at the material's failure strain and the default
// filter (4 element lengths).
std::unique_ptr<FabricEngine> struckPly() {
  WeaveParams p = km2_706();
  p.nx = p.ny = 9;  // 18 x 18 yarns of 0.747 mm: 13.4 mm
  p.cpPerSpan = 1;
  auto e = std::make_unique<FabricEngine>(buildWeave(p).fabric);
  ContactParams c;
  c.positionCorrection = 0, c.flattenPasses = 1, c.maxIterations = 10;
  e->enableCollisions(c, BroadPhase::Grid);
  e->collisions()->settle(e->fabric());
  for (const Yarn& y : e->fabric().yarns) e->dynamics().fix(y.firstNode), e->dynamics().fix(y.firstNode + y.nNodes - 1);
  BreakageParams b;
  b.enabled = true;
  e->dynamics().configureBreakage(b);
  e->collisions()->bodies.push_back(cubeAbove(e->fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -300)));
  return e;
}

}  // namespace

TEST(Reliability, RestartAfterBreaksIsBitForBit) {
  const std::string path = tempPath("ply");
  auto a = struckPly();
  const Real dt = 0.7 * a->criticalDt();
  // Breaks start at step 103 (measured): the file holds broken elements, and more break after it.
  const int saveAt = 120, end = 190;
  for (int s = 0; s < saveAt; ++s) a->step(dt);
  const long brokenAtSave = a->dynamics().breakage().brokenElements();
  EXPECT_GT(brokenAtSave, 0);
  a->saveState(path);
  const RigidBody body = a->collisions()->bodies[0];  // YADE keeps the body's state: copied here
  for (int s = saveAt; s < end; ++s) a->step(dt);

  auto b = struckPly();
  b->collisions()->bodies[0] = body;
  b->setState(loadState(path, b->fabric().nNodes()));
  for (int s = saveAt; s < end; ++s) b->step(dt);

  const long brokenA = a->dynamics().breakage().brokenElements();
  EXPECT_GT(brokenA, brokenAtSave + 2) << "the cube breaks elements after the restart point";
  EXPECT_EQ(b->dynamics().breakage().brokenElements(), brokenA);
  EXPECT_TRUE(sameBits(a->fabric().alive, b->fabric().alive));
  EXPECT_TRUE(sameBits(a->fabric().pos, b->fabric().pos));
  EXPECT_TRUE(sameBits(a->fabric().vel, b->fabric().vel));
  EXPECT_TRUE(sameBits(a->dynamics().breakage().filteredStrain(), b->dynamics().breakage().filteredStrain()));
  const EnergyBooks ba = a->dynamics().books(), bb = b->dynamics().books();
  EXPECT_EQ(std::memcmp(&ba, &bb, sizeof(EnergyBooks)), 0) << "energy books";
  EXPECT_EQ(std::memcmp(b->collisions()->bodies[0].vel.data(), a->collisions()->bodies[0].vel.data(), sizeof(Vec3)), 0);
  std::remove(path.c_str());
}

// A state loaded into an engine that had started from rest: its books come from the file, so the
// next step is not taken for an energy blow-up (the old books had initial = 0).
TEST(Reliability, LoadStateSetsTheEnergyBooks) {
  const std::string path = tempPath("books");
  auto a = movedChain();
  a->saveState(path);
  FabricEngine b(straightChain(32, 1e-3));
  const Real dt = 0.8 * b.criticalDt();
  b.step(dt);  // at rest: initial energy 0
  b.setState(loadState(path));
  const EnergyBooks ba = a->dynamics().books(), bb = b.dynamics().books();
  EXPECT_EQ(std::memcmp(&ba, &bb, sizeof(EnergyBooks)), 0);
  EXPECT_NO_THROW(b.step(dt));
  a->step(dt);
  EXPECT_TRUE(sameBits(a->fabric().pos, b.fabric().pos));
  std::remove(path.c_str());
}

// --- defect 3: load_state validates everything, then commits ---

TEST(Reliability, RefusedStatesChangeNothing) {
  const std::string path = tempPath("bad");
  auto src = movedChain();
  const KinematicState good = src->state();
  auto target = movedChain();
  target->step(0.5 * target->criticalDt());  // differs from src
  const Vec3Array pos0 = target->fabric().pos, vel0 = target->fabric().vel;
  const long step0 = target->dynamics().stepCount();

  auto refused = [&](const KinematicState& s, const std::string& what) {
    saveState(path, s);  // a valid file (checksum and all) holding bad values
    std::string param;
    try {
      target->setState(loadState(path, target->fabric().nNodes()));
    } catch (const ParameterError& e) {
      param = e.parameter();
    }
    EXPECT_NE(param, "") << what << " was accepted";
    EXPECT_TRUE(sameBits(target->fabric().pos, pos0)) << what << " changed the positions";
    EXPECT_TRUE(sameBits(target->fabric().vel, vel0)) << what << " changed the velocities";
    EXPECT_EQ(target->dynamics().stepCount(), step0) << what;
  };
  KinematicState s = good;
  s.time = NAN;
  refused(s, "time NaN");
  s = good, s.step = -1;
  refused(s, "step -1");
  s = good, s.lastDt = 1e300;
  refused(s, "last_dt 1e300");
  s = good, s.lastDt = -1;
  refused(s, "last_dt -1");
  for (Real eps : {Real(NAN), Real(1), Real(5), Real(-1)}) {
    s = good, s.flat[3] = eps;
    refused(s, "section flattening " + fmt(eps));
  }
  s = good, s.dir[4] = Vec3(NAN, 0, 0);
  refused(s, "section direction NaN");
  s = good, s.dir[4] = Vec3::Zero();
  refused(s, "section direction 0");
  s = good, s.pos[5].x() = INFINITY;
  refused(s, "position inf");
  s = good, s.alive[2] = 0;  // broken but still stiff
  refused(s, "a broken element with stiffness");
  s = good, s.stiffness[2] = NAN;
  refused(s, "a NaN stiffness");
  s = good, s.books.initial = NAN;
  refused(s, "energy book NaN");

  // Bytes: trailing bytes, a flipped bit, a truncated file.
  saveState(path, good);
  const std::string bytes = readAll(path);
  for (const std::string& bad : {bytes + "x", bytes.substr(0, bytes.size() - 1), bytes.substr(0, 40),
                                 [&] { std::string b = bytes; b[200] ^= 1; return b; }()}) {
    writeAll(path, bad);
    EXPECT_EQ(parameterOf([&] { target->setState(loadState(path)); }), "state");
    EXPECT_TRUE(sameBits(target->fabric().pos, pos0));
  }
  // A state of another weave with the same node count (longer elements; a denser material).
  YarnMaterial dense = km2Material();
  dense.rho *= 1.01;
  FabricEngine denser(straightChain(32, 1e-3, dense));
  saveState(path, denser.state());
  EXPECT_EQ(parameterOf([&] { target->setState(loadState(path, target->fabric().nNodes())); }), "state");
  FabricEngine other(straightChain(32, 1.1e-3));
  saveState(path, other.state());
  EXPECT_EQ(parameterOf([&] { target->setState(loadState(path, target->fabric().nNodes())); }), "state");
  EXPECT_TRUE(sameBits(target->fabric().pos, pos0));
  // The good one loads.
  saveState(path, good);
  target->setState(loadState(path));
  EXPECT_TRUE(sameBits(target->fabric().pos, good.pos));
  std::remove(path.c_str());
}

// --- defect 4: atomic, checked writes ---

TEST(Reliability, SaveStateReportsWriteErrorsAndRefusesNul) {
  auto e = movedChain();
  EXPECT_THROW(e->saveState("/dev/full"), std::runtime_error);
  const std::string withNul = tempPath("nul") + std::string(1, '\0') + "tail";
  EXPECT_EQ(parameterOf([&] { e->saveState(withNul); }), "path");
  EXPECT_EQ(parameterOf([&] { loadState(withNul); }), "path");
  EXPECT_NE(::access(withNul.c_str(), F_OK), 0) << "nothing written at the truncated path";
  EXPECT_THROW(e->saveState("/nonexistent-folder/x.state"), std::runtime_error);
}

// A write that fails half-way (here: the file size limit, as a full disk or a kill would) leaves the
// previous checkpoint whole and no temporary behind; the old code truncated the file first.
TEST(Reliability, FailedSaveKeepsThePreviousFile) {
  const std::string dir = ::testing::TempDir() + "woven_rel_atomic_" + std::to_string(::getpid());
  ASSERT_EQ(::mkdir(dir.c_str(), 0700), 0);
  const std::string path = dir + "/ply.state";
  auto small = movedChain(8);
  small->saveState(path);
  const std::string before = readAll(path);
  ASSERT_GT(before.size(), 0u);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit lim{static_cast<rlim_t>(before.size() + 100), static_cast<rlim_t>(before.size() + 100)};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    auto big = movedChain(2000);  // a larger fabric: its file does not fit under the limit
    try {
      woven::saveState(path, big->state());
    } catch (const std::runtime_error&) {
      ::_exit(0);  // the failure was reported
    }
    ::_exit(1);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the failed write was not reported";
  EXPECT_EQ(readAll(path), before) << "the previous file was damaged";
  int entries = 0;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (dirent* ent = ::readdir(d)) entries += ent->d_name[0] != '.';
    ::closedir(d);
  }
  EXPECT_EQ(entries, 1) << "a temporary was left behind";
  std::remove(path.c_str());
  ::rmdir(dir.c_str());
}

// --- defect 5: read-only queries ---

TEST(Reliability, OverlapQueriesDoNotChangeTheTrajectory) {
  auto make = [] {
    WeaveParams p = km2_706();
    p.nx = p.ny = 3;
    p.cpPerSpan = 2;
    p.warpMaterial.dampingRatio = p.weftMaterial.dampingRatio = 0.1;
    auto e = std::make_unique<FabricEngine>(buildWeave(p).fabric);
    e->enableCollisions(ContactParams());
    e->collisions()->settle(e->fabric());
    for (const Yarn& y : e->fabric().yarns)
      if (y.family == YarnFamily::Warp) {
        e->dynamics().fix(y.firstNode);
        e->dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(3, 0.5, 0.2));
      }
    RigidBody ball;
    RigidPart part;
    part.type = RigidPart::Type::Sphere, part.radius = 0.5e-3;
    ball.parts.push_back(part);
    ball.mass = 0, ball.pos = Vec3(0, 0, 5e-3);  // kinematic, far above: no contact
    e->collisions()->bodies.push_back(ball);
    return e;
  };
  auto a = make(), b = make();
  const Real dt = 0.7 * a->criticalDt();
  for (int s = 0; s < 60; ++s) {
    a->step(dt), b->step(dt);
    if (s % 7 == 3) {
      b->collisions()->overlap(b->fabric());
      b->collisions()->bodyOverlap(b->fabric(), 0);
    }
  }
  EXPECT_TRUE(sameBits(a->fabric().secDir, b->fabric().secDir));
  EXPECT_TRUE(sameBits(a->fabric().pos, b->fabric().pos));
  EXPECT_TRUE(sameBits(a->fabric().vel, b->fabric().vel));
  EXPECT_EQ(a->collisions()->stats.contacts, b->collisions()->stats.contacts);
}
