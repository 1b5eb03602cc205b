// A checkpoint is a pure observation: the straight run, the run that saves (state
// files and snapshots, several times, while contacts are active and elements break) and the runs
// resumed from each save are the same bits. The collision stage's memory (persistent crossings,
// pairs' measure memory, last body contacts) travels in the state file and the snapshot; before, a
// save forgot it and the saving run left the straight one (3.4 mm, 460 m/s, 10 against 4 breaks).
#include "body_util.hpp"
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "engine/Snapshot.hpp"
#include "fabric/StateIO.hpp"
#include "same_bits.hpp"
#include "weave/WeaveBuilder.hpp"
#include <gtest/gtest.h>
#include <cstdio>
#include <cstring>
#include <unistd.h>

using namespace woven;
using namespace woven_test;

namespace {

struct Scene {
  ContactModel model = ContactModel::Gap;
  Crossings crossings = Crossings::Persistent;
  bool breakage = true;
};

// A 13.4 mm KM2 ply (one CP per span, ends clamped) struck by a 3 mm, 1 g cube at 300 m/s: the cube
// touches at step ~60 and breaks elements from step ~100 (breakage on).
std::unique_ptr<FabricEngine> struckPly(const Scene& sc) {
  WeaveParams p = km2_706();
  p.nx = p.ny = 9;
  p.cpPerSpan = 1;
  auto e = std::make_unique<FabricEngine>(buildWeave(p).fabric);
  ContactParams c;
  c.model = sc.model, c.crossings = sc.crossings;
  c.positionCorrection = 0, c.flattenPasses = 1, c.maxIterations = 10;
  e->enableCollisions(c, BroadPhase::Grid);
  e->collisions()->settle(e->fabric());
  for (const Yarn& y : e->fabric().yarns) e->dynamics().fix(y.firstNode), e->dynamics().fix(y.firstNode + y.nNodes - 1);
  BreakageParams b;
  b.enabled = sc.breakage;
  e->dynamics().configureBreakage(b);
  e->collisions()->bodies.push_back(cubeAbove(e->fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -300)));
  return e;
}

void expectSame(FabricEngine& a, FabricEngine& b, const std::string& what) {
  SCOPED_TRACE(what);
  expectSameRun(a, b);
}

void checkpointIsAnObservation(const Scene& sc) {
  // The cube touches at ~60; breaks from ~100. Sanitizer builds stop 10 steps after the last save
  // (the paper model's run was 95 s of their tier).
  const int end = kSlowBuild ? 150 : 200, saveAt[3] = {60, 100, 140};
  auto straight = struckPly(sc);
  const Real dt = 0.7 * straight->criticalDt();
  for (int s = 0; s < end; ++s) straight->step(dt);
  if (sc.breakage) {
    EXPECT_GT(straight->dynamics().breakage().brokenElements(), 0) << "the cube breaks elements";
  }

  // The saving run: a state file at 60 and 140, a snapshot at 100.
  auto saving = struckPly(sc);
  std::string files[2], snapshot;
  RigidBody bodyAt[2];  // YADE keeps the body's state beside a state file: copied here
  long crossingsAtSave = 0, contactsAtSave = 0;
  for (int s = 0, f = 0; s < end; ++s) {
    if (s == saveAt[1]) {
      snapshot = engineSnapshot(*saving);
    } else if (s == saveAt[0] || s == saveAt[2]) {
      files[f] = ::testing::TempDir() + "woven_ckp_" + std::to_string(::getpid()) + "_" + std::to_string(s) + ".state";
      saving->saveState(files[f]);
      bodyAt[f++] = saving->collisions()->bodies[0];
    }
    if (s == saveAt[1] || s == saveAt[2]) {
      crossingsAtSave += static_cast<long>(saving->collisions()->crossings().crossings().size());
      contactsAtSave += saving->collisions()->stats.contacts + saving->collisions()->stats.bodyContacts;
    }
    saving->step(dt);
  }
  if (sc.crossings == Crossings::Persistent && sc.model == ContactModel::Gap) {
    EXPECT_GT(crossingsAtSave, 0);
  }
  EXPECT_GT(contactsAtSave, 0) << "contacts active at the saves";
  expectSame(*straight, *saving, "the saving run against the straight run");

  for (int f = 0; f < 2; ++f) {
    auto resumed = struckPly(sc);
    resumed->collisions()->bodies[0] = bodyAt[f];
    resumed->setState(loadState(files[f], resumed->fabric().nNodes()));
    for (int s = saveAt[2 * f]; s < end; ++s) resumed->step(dt);
    expectSame(*straight, *resumed, "resumed from the state file of step " + std::to_string(saveAt[2 * f]));
    std::remove(files[f].c_str());
  }
  auto restored = restoreSnapshot(snapshot);
  for (int s = saveAt[1]; s < end; ++s) restored->step(dt);
  expectSame(*straight, *restored, "restored from the snapshot of step 100");
}

}  // namespace

TEST(Checkpoint, PersistentCrossingsWithBreakage) { checkpointIsAnObservation(Scene{}); }

// Sanitizer builds run the default (persistent crossings, breakage) and the paper model's memory,
// the two layouts of the stage's memory; the Release tests all four (the four took 152 s of the
// sanitizer tier's 371).
TEST(Checkpoint, PersistentCrossingsWithoutBreakage) {
  if (kSlowBuild) GTEST_SKIP() << "sanitizer build: the Release tests run it";
  Scene s;
  s.breakage = false;
  checkpointIsAnObservation(s);
}

TEST(Checkpoint, ChordContactsWithBreakage) {
  if (kSlowBuild) GTEST_SKIP() << "sanitizer build: the Release tests run it";
  Scene s;
  s.crossings = Crossings::Chords;
  checkpointIsAnObservation(s);
}

TEST(Checkpoint, PaperModelWithBreakage) {
  Scene s;
  s.model = ContactModel::Paper;
  checkpointIsAnObservation(s);
}
