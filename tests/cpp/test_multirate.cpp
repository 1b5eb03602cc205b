// Multi-rate springs (FabricEngine::setMultiRate, ChainDynamics::setSlowElements: r-RESPA's impulse
// form over the elements). The slow elements are those whose nodes' Gershgorin bound allows the long
// step, which for a uniform chain is the chain's own limit exactly; a chain of fine and coarse CPs
// stepped so conserves momentum to rounding and energy within the leapfrog's swing, and follows the
// single-rate run of its substeps; a fabric with nothing slow keeps the single-rate bits.
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include <gtest/gtest.h>
#include <cmath>

using namespace woven;
using namespace woven_test;

namespace {

// A free linear yarn (no tension-only clamp, no damping) of `fine` CPs of 0.25 mm, then `coarse`
// CPs of 1 mm: node masses m (fine), 4 m (coarse), 2.5 m where they meet; stiffnesses K and K / 4.
Fabric fineCoarseChain(int fine, int coarse) {
  Vec3Array pts{Vec3::Zero()};
  for (int i = 0; i < fine; ++i) pts.push_back(pts.back() + Vec3(0.25e-3, 0, 0));
  for (int i = 0; i < coarse; ++i) pts.push_back(pts.back() + Vec3(1e-3, 0, 0));
  Fabric f;
  f.addYarn(pts, km2Material(0.0, false), YarnSection());
  // An axial wave over the whole yarn (the springs work in both parts) and a drift.
  for (Index i = 0; i < f.nNodes(); ++i) f.vel[i] = Vec3(2 * std::sin(0.37 * i) + 0.5, 0.1, 0);
  return f;
}

Real totalEnergy(const EnergyBooks& b) { return b.kinetic + b.elastic; }

}  // namespace

// Gershgorin's node bound sqrt(2 m_i / sum K) is, for a uniform chain, sqrt(m_e / K) = dt_crit at
// every node (interior: m_e and 2K; end: m_e / 2 and K): every element is slow just below it and
// none just above.
TEST(MultiRate, UniformChainIsSlowExactlyBelowItsCriticalStep) {
  const Fabric f = straightChain(30, 0.25e-3, km2Material(0.0, false));
  const Real dtc = criticalTimeStep(f);
  for (std::uint8_t s : slowElements(f, 0.999 * dtc)) EXPECT_EQ(s, 1);
  for (std::uint8_t s : slowElements(f, 1.001 * dtc)) EXPECT_EQ(s, 0);
}

// Fine CPs (limit dt_crit), coarse ones (4 dt_crit at a coarse node: 4 m over K / 2) and the node
// where they meet (2.5 m over 1.25 K: 2 dt_crit). At 3.5 dt_crit the fine CPs and the coarse CP at
// the junction are fast, the other coarse ones (the free end's node: 2 m over K / 4, 4 dt_crit) slow.
TEST(MultiRate, SlowElementsAreTheCoarseOnesAwayFromTheFine) {
  const Fabric f = fineCoarseChain(8, 6);
  const std::vector<std::uint8_t> slow = slowElements(f, 3.5 * criticalTimeStep(f));
  const std::vector<std::uint8_t> expected{0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1};
  EXPECT_EQ(slow, expected);
  // Just above 2 dt_crit the junction's coarse CP is slow too; just above 4 dt_crit no coarse one is.
  EXPECT_EQ(slowElements(f, 1.99 * criticalTimeStep(f))[8], 1);
  for (std::uint8_t s : slowElements(f, 4.01 * criticalTimeStep(f))) EXPECT_EQ(s, 0);
}

// Four substeps per step at 0.7 x 4 dt_crit, the coarse CPs once per step (at 0.7 of their own
// limit): impulses are internal and the kicks of both rates symmetric, so the momentum holds to
// rounding. The energy at each step's end swings as the plain leapfrog's does on a uniform chain at
// 0.7 of its limit (the coarse CPs alone, stepped plainly: measured alongside; within 2x, for the
// junction), and the swing over the last 1000 of 3000 steps is no larger than over the first 1000
// (bounded: no resonance of the fast CPs with the slow kicks).
TEST(MultiRate, FineCoarseChainKeepsMomentumAndEnergy) {
  FabricEngine multi(fineCoarseChain(12, 12)), plain(fineCoarseChain(0, 24));
  multi.setSubsteps(4);
  multi.setMultiRate(true);
  ASSERT_EQ(multi.dynamics().slowElementMask().size(), 24u);
  int slowCount = 0;
  for (std::uint8_t s : multi.dynamics().slowElementMask()) slowCount += s;
  EXPECT_EQ(slowCount, 11) << "the coarse CPs but the one at the junction (stable up to 4 dt_crit: at 4 x dt_crit)";
  const auto p = [](const FabricEngine& e) {
    Vec3 s = Vec3::Zero();
    for (Index i = 0; i < e.fabric().nNodes(); ++i) s += e.fabric().mass[i] * e.fabric().vel[i];
    return s;
  };
  const Vec3 p0 = p(multi);
  const Real e0 = totalEnergy(multi.dynamics().energy()), e0Plain = totalEnergy(plain.dynamics().energy());
  Real swing[3] = {0, 0, 0}, swingPlain = 0;
  for (int k = 0; k < 3000; ++k) {
    multi.step(0.7 * multi.maxStep()), plain.step(0.7 * plain.maxStep());
    swing[k / 1000] = std::max(swing[k / 1000], std::abs(totalEnergy(multi.dynamics().energy()) - e0) / e0);
    swingPlain = std::max(swingPlain, std::abs(totalEnergy(plain.dynamics().energy()) - e0Plain) / e0Plain);
    ASSERT_LT((p(multi) - p0).norm(), 1e-12 * p0.norm()) << "step " << k;
  }
  EXPECT_GT(swingPlain, 0);
  EXPECT_LT(swing[0], 2 * swingPlain) << "plain leapfrog's swing " << swingPlain;
  EXPECT_LT(swing[2], 2 * swingPlain);
  EXPECT_LE(swing[2], swing[0] * 1.05) << "first 1000 steps " << swing[0] << ", last " << swing[2];
}

// The same chain, multi-rate against every spring at the substep, over 1000 steps: the node
// positions agree to a small part of how far the wave moved them (both second order in the step).
TEST(MultiRate, FollowsTheSingleRateRun) {
  FabricEngine multi(fineCoarseChain(12, 12)), single(fineCoarseChain(12, 12));
  multi.setSubsteps(4), single.setSubsteps(4);
  multi.setMultiRate(true);
  const Fabric start = fineCoarseChain(12, 12);
  const Real dt = 0.7 * multi.maxStep();
  for (int k = 0; k < 1000; ++k) multi.step(dt), single.step(dt);
  Real apart = 0, moved = 0;
  for (Index i = 0; i < start.nNodes(); ++i) {
    apart = std::max(apart, (multi.fabric().pos[i] - single.fabric().pos[i]).norm());
    // the wave's part of the motion (the drift of 0.5 m/s and 0.1 m/s is common)
    moved = std::max(moved, (single.fabric().pos[i] - start.pos[i] - 1000 * dt * Vec3(0.5, 0.1, 0)).norm());
  }
  EXPECT_GT(moved, 0);
  EXPECT_LT(apart, 0.05 * moved) << apart << " m apart, wave displacement " << moved << " m";
}

// With nothing slow (a uniform chain at 4 x its limit) or multi-rate off, the bits are those of the
// single-rate substeps.
TEST(MultiRate, NothingSlowKeepsTheBits) {
  FabricEngine a(straightChain(20, 0.25e-3, km2Material(0.0, false))), b(straightChain(20, 0.25e-3, km2Material(0.0, false)));
  for (Index i = 0; i < a.fabric().nNodes(); ++i)
    a.fabric().vel[i] = b.fabric().vel[i] = Vec3(std::sin(0.5 * i), 0, 0);
  a.setSubsteps(4), b.setSubsteps(4);
  a.setMultiRate(true);
  for (int k = 0; k < 100; ++k) a.step(0.7 * a.maxStep()), b.step(0.7 * b.maxStep());
  EXPECT_TRUE(a.dynamics().slowElementMask().empty());
  for (Index i = 0; i < a.fabric().nNodes(); ++i) {
    EXPECT_EQ(a.fabric().pos[i], b.fabric().pos[i]) << "node " << i;
    EXPECT_EQ(a.fabric().vel[i], b.fabric().vel[i]) << "node " << i;
  }
}

// Turning multi-rate off or on between steps (or other substeps) re-splits the kick the last step
// still owes: the synchronised velocities, so the energy books, are the same before and after (to
// rounding), and the run goes on with the energy within the same swing, at any accepted dt.
TEST(MultiRate, ChangingTheSplitKeepsTheSynchronisedState) {
  FabricEngine e(fineCoarseChain(12, 12));
  e.setSubsteps(4);
  e.setMultiRate(true);
  const Real e0 = totalEnergy(e.dynamics().energy());
  for (int k = 0; k < 300; ++k) e.step(0.7 * e.maxStep());
  std::vector<Vec3> before;
  for (Index i = 0; i < e.fabric().nNodes(); ++i) before.push_back(e.dynamics().syncVelocity(i));
  const Real e1 = totalEnergy(e.dynamics().energy());
  e.setMultiRate(false);
  EXPECT_NEAR(totalEnergy(e.dynamics().energy()), e1, 1e-12 * e1);
  for (Index i = 0; i < e.fabric().nNodes(); ++i)
    EXPECT_LT((e.dynamics().syncVelocity(i) - before[i]).norm(), 1e-12 * (1 + before[i].norm())) << "node " << i;
  e.setMultiRate(true);
  Real swing = 0;
  for (int k = 0; k < 300; ++k) {
    e.step((k < 150 ? 0.7 : 0.35) * e.maxStep());
    swing = std::max(swing, std::abs(totalEnergy(e.dynamics().energy()) - e0) / e0);
  }
  EXPECT_EQ(e.dynamics().slowElementMask()[12], 0) << "the junction's coarse CP stays fast";
  EXPECT_EQ(e.dynamics().slowElementMask()[13], 1);
  EXPECT_LT(swing, 0.03);
}
