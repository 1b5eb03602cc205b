// The collision stage's settings as plain data (pkg/engine/HostBridge.hpp, what the YADE plugin's
// stage objects show and set): every field lands on its ContactParams member (checked against the
// members written out here, not through the bridge's own mapping), reads back as set, bad input and
// collisions off are refused with the stage unchanged.
#include "core/Errors.hpp"
#include "engine/FabricEngine.hpp"
#include "engine/HostBridge.hpp"
#include "weave/WeaveBuilder.hpp"
#include <gtest/gtest.h>

using namespace woven;

namespace {

std::unique_ptr<FabricEngine> smallPly() {
  WeaveParams p = km2_706();
  p.nx = p.ny = 2;
  p.cpPerSpan = 1;
  return std::make_unique<FabricEngine>(buildWeave(p).fabric);
}

// Every field away from its default, each to a value allowed with the others.
HostStageParams changed() {
  HostStageParams h;
  hostStageDefaults(h);
  h.sectionRule = "paper", h.flattening = "springs", h.mcd = 0.45, h.flattenPasses = 7, h.margin = 3e-6;
  h.broadPhase = "grid", h.skin = 7e-6, h.selfExclude = 3, h.yarnContacts = false, h.threads = 2;
  h.model = "gap", h.cacheDistance = 2e-7;
  h.penaltyStiffness = 3e5, h.penaltyDamping = 0.25, h.sectionStiffness = 2e4;
  h.response = "impulse", h.sweepOrder = "coloured";
  h.restitution = 0.3, h.friction = 0.4, h.bodyFriction = 0.5, h.tolerance = 2e-6, h.positionCorrection = 0.35;
  h.correctionSlop = 0.7e-6, h.projectionSlop = 0.8e-6, h.projectionMaxMove = 20e-6, h.maxIterations = 33;
  h.projectionSweeps = 5, h.projectionCheck = 3e-6;
  return h;
}

}  // namespace

TEST(HostBridge, StageParamsReachTheCoreAndReadBack) {
  auto ep = smallPly();
  FabricEngine& e = *ep;
  HostStageParams off;
  hostStageParams(e, off);
  EXPECT_FALSE(off.collisions);
  EXPECT_THROW(hostSetStageParams(e, changed()), ParameterError);  // collisions off: refused
  EXPECT_EQ(e.collisions(), nullptr);

  e.enableCollisions(ContactParams());
  const HostStageParams h = changed();
  hostSetStageParams(e, h);
  const CollisionStage& st = *e.collisions();
  const ContactParams& c = st.params();
  EXPECT_EQ(c.rule, SectionRule::Paper);
  EXPECT_EQ(c.flattening, Flattening::Springs);
  EXPECT_EQ(c.mcd, 0.45);
  EXPECT_EQ(c.flattenPasses, 7);
  EXPECT_EQ(c.margin, 3e-6);
  EXPECT_EQ(st.broadPhase, BroadPhase::Grid);
  EXPECT_EQ(c.skin, 7e-6);
  EXPECT_EQ(c.selfExclude, 3);
  EXPECT_FALSE(c.yarnContacts);
  EXPECT_EQ(c.threads, 2);
  EXPECT_EQ(c.model, ContactModel::Gap);
  EXPECT_EQ(c.cacheDistance, 2e-7);
  EXPECT_EQ(c.penaltyStiffness, 3e5);
  EXPECT_EQ(c.penaltyDamping, 0.25);
  EXPECT_EQ(c.sectionStiffness, 2e4);
  EXPECT_EQ(c.response, Response::Impulse);
  EXPECT_EQ(c.sweepOrder, SweepOrder::Coloured);
  EXPECT_EQ(c.restitution, 0.3);
  EXPECT_EQ(c.friction, 0.4);
  EXPECT_EQ(c.bodyFriction, 0.5);
  EXPECT_EQ(c.tolerance, 2e-6);
  EXPECT_EQ(c.positionCorrection, 0.35);
  EXPECT_EQ(c.correctionSlop, 0.7e-6);
  EXPECT_EQ(c.projectionSlop, 0.8e-6);
  EXPECT_EQ(c.projectionMaxMove, 20e-6);
  EXPECT_EQ(c.maxIterations, 33);
  EXPECT_EQ(c.projectionSweeps, 5);
  EXPECT_EQ(c.projectionCheck, 3e-6);

  HostStageParams back;
  hostStageParams(e, back);
  EXPECT_TRUE(back.collisions);
  EXPECT_EQ(back.sectionRule, h.sectionRule);
  EXPECT_EQ(back.flattening, h.flattening);
  EXPECT_EQ(back.broadPhase, h.broadPhase);
  EXPECT_EQ(back.model, h.model);
  EXPECT_EQ(back.response, h.response);
  EXPECT_EQ(back.sweepOrder, h.sweepOrder);
  EXPECT_EQ(back.friction, h.friction);
  EXPECT_EQ(back.maxIterations, h.maxIterations);
  EXPECT_EQ(back.selfExclude, h.selfExclude);

  // The other names the bridge writes read back too.
  HostStageParams sap = h;
  sap.broadPhase = "sap", sap.model = "paper", sap.response = "penalty", sap.sweepOrder = "sequential";
  sap.sectionRule = "constant_area", sap.flattening = "none", sap.friction = 0, sap.bodyFriction = 0;
  sap.projectionSweeps = 0;
  hostSetStageParams(e, sap);
  hostStageParams(e, back);
  EXPECT_EQ(back.broadPhase, "sap");
  EXPECT_EQ(back.model, "paper");
  EXPECT_EQ(back.response, "penalty");
  EXPECT_EQ(back.sweepOrder, "sequential");
  EXPECT_EQ(back.sectionRule, "constant_area");
  EXPECT_EQ(back.flattening, "none");
  sap.sweepOrder = "blocked";
  hostSetStageParams(e, sap);
  hostStageParams(e, back);
  EXPECT_EQ(back.sweepOrder, "blocked");
}

TEST(HostBridge, BadStageParamsAreRefusedUnchanged) {
  auto ep = smallPly();
  FabricEngine& e = *ep;
  e.enableCollisions(ContactParams());
  HostStageParams h = changed();
  h.restitution = 2;
  try {
    hostSetStageParams(e, h);
    FAIL() << "restitution 2 accepted";
  } catch (const ParameterError& err) {
    EXPECT_EQ(err.parameter(), "restitution");
  }
  h = changed();
  h.broadPhase = "octree";
  try {
    hostSetStageParams(e, h);
    FAIL() << "broad phase 'octree' accepted";
  } catch (const ParameterError& err) {
    EXPECT_EQ(err.parameter(), "broad_phase");
  }
  // nothing of either attempt landed
  EXPECT_EQ(e.collisions()->params().friction, 0.0);
  EXPECT_EQ(e.collisions()->broadPhase, BroadPhase::YarnTree);
  EXPECT_EQ(e.collisions()->params().mcd, ContactParams().mcd);
}
