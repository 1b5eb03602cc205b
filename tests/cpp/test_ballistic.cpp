// Ballistic pieces: yarn breakage (filtered strain against the raw one on Smith's impact, Weibull
// strengths, released energy) and rigid bodies colliding with yarns (momentum exchange, no
// tunnelling at 1000 m/s, restitution, the moving test, bad input).
#include "body_util.hpp"
#include "chain_util.hpp"
#include "yarn_util.hpp"
#include "engine/FabricEngine.hpp"
#include "geom/BodyContact.hpp"
#include <gtest/gtest.h>
#include <cmath>

using namespace woven;
using namespace woven_test;

namespace {

Real smithSpeed(Real eps, Real c) { return c * std::sqrt(2 * eps * std::sqrt(eps * (1 + eps)) - eps * eps); }

struct SmithRun {
  long broken = 0;
  Real maxRaw = 0, maxFiltered = 0, firstBreak = -1;
};

// Smith's transverse impact: a straight KM2 yarn 80 mm long in CPs of l0, ends fixed, the middle node
// driven transversely at the speed whose plateau strain is `plateau`; breakage at 5 % with the given
// filter length [m]; run for `duration` [s] (the longitudinal wave does not reach the ends).
SmithRun smith(Real plateau, Real filterLength, Real duration, Real l0 = 0.2e-3) {
  const int n = 2 * static_cast<int>(0.04 / l0);
  FabricEngine e(straightChain(n, l0));
  const Real c = std::sqrt(90e9 / 1440);
  e.dynamics().fix(0);
  e.dynamics().fix(n);
  e.dynamics().prescribeVelocity(n / 2, Vec3(0, 0, smithSpeed(plateau, c)));
  BreakageParams p;
  p.enabled = true, p.threshold = 0.05, p.filterLength = filterLength;
  e.dynamics().configureBreakage(p);
  const Real dt = 0.7 * e.criticalDt();
  SmithRun r;
  for (long k = 0, steps = static_cast<long>(duration / dt); k < steps; ++k) {
    e.step(dt);
    const auto& f = e.dynamics().breakage().filteredStrain();
    for (Index el = 0; el < n; ++el) {
      if (!e.fabric().alive[el]) continue;
      r.maxRaw = std::max(r.maxRaw, e.fabric().strain[el]);
      r.maxFiltered = std::max(r.maxFiltered, f[el]);
    }
    if (e.dynamics().breakage().brokenElements() > 0 && r.firstBreak < 0)
      r.firstBreak = e.dynamics().breakage().log()[0].time;
  }
  r.broken = e.dynamics().breakage().brokenElements();
  return r;
}

}  // namespace

// The raw element strain overshoots Smith's plateau at the front (measured here: 1.04x at a Courant
// number of 0.7, where physics-reference.md allows up to ~1.27x): with a plateau 3 % below the failure
// strain the raw measure breaks the yarn, the filtered one (1 mm: tau = 0.13 us) does not, and it
// still breaks a yarn whose plateau is 10 % above the threshold within 1 us.
TEST(Breakage, FilteredStrainIgnoresTheDispersionSpikeRawDoesNot) {
  const Real duration = 4e-6;  // 700 steps of 400 CPs: short in every build
  const SmithRun raw = smith(0.97 * 0.05, 0.0, duration);
  const SmithRun filtered = smith(0.97 * 0.05, 1e-3, duration);
  EXPECT_GT(raw.broken, 0) << "raw max strain " << raw.maxRaw;
  EXPECT_EQ(filtered.broken, 0) << "filtered max strain " << filtered.maxFiltered;
  EXPECT_LT(filtered.maxFiltered, 0.05);
  const SmithRun over = smith(1.1 * 0.05, 1e-3, 1e-6);
  EXPECT_GT(over.broken, 0);
  EXPECT_LT(over.firstBreak, 1e-6);
}

// The default filter, 4 element lengths, follows the resolution: with 0.75 mm CPs a fixed 1 mm
// filter still broke the yarn at 90 % of the failure strain; 4 l0 (3 mm) does not at 97 %, and breaks
// at 110 % within 1.5 us.
TEST(Breakage, DefaultFilterFollowsTheElementLength) {
  const Real l0 = 0.75e-3;
  EXPECT_GT(smith(0.90 * 0.05, 1e-3, 4e-6, l0).broken, 0);
  EXPECT_EQ(smith(0.97 * 0.05, BreakageParams().filterLength, 4e-6, l0).broken, 0);
  EXPECT_EQ(smith(0.97 * 0.05, BreakageParams().filterLength, 4e-6).broken, 0);  // and with 0.2 mm CPs
  const SmithRun over = smith(1.1 * 0.05, BreakageParams().filterLength, 1.5e-6, l0);
  EXPECT_GT(over.broken, 0);
  EXPECT_LT(over.firstBreak, 1.5e-6);
}

// A broken element releases exactly its elastic energy 1/2 K (l - l0)^2, leaves the books
// balanced, and carries no force afterwards.
TEST(Breakage, ReleasesTheElementsElasticEnergyIntoItsBook) {
  const int n = 20;
  FabricEngine e(straightChain(n, 1e-3));
  e.dynamics().fix(0);
  e.dynamics().prescribeVelocity(n, Vec3(2.0, 0, 0));  // pulls the chain apart slowly
  BreakageParams p;
  p.enabled = true, p.threshold = 0.002, p.filterLength = 0;
  e.dynamics().configureBreakage(p);
  const Real dt = 0.7 * e.criticalDt();
  Real elasticBefore = 0;
  Real errBefore = 0;
  while (e.dynamics().breakage().brokenElements() == 0 && e.dynamics().stepCount() < 200000) {
    elasticBefore = e.dynamics().energy().elastic;
    errBefore = e.dynamics().energy().balanceError();
    e.step(dt);
  }
  ASSERT_EQ(e.dynamics().breakage().brokenElements(), 1);
  const BreakEvent& ev = e.dynamics().breakage().log()[0];
  const EnergyBooks b = e.dynamics().energy();
  EXPECT_GT(ev.energy, 0);
  EXPECT_NEAR(b.released, ev.energy, 1e-15);
  EXPECT_GT(ev.rawStrain, 0.002);
  EXPECT_EQ(e.fabric().stiffness[ev.element], 0.0);
  // Energy of one element of a chain at uniform strain: about 1/n of the chain's.
  EXPECT_NEAR(ev.energy / elasticBefore, 1.0 / n, 0.5 / n);
  // The books move at the break by what the leapfrog's synchronised velocity v_{n+1/2} + dt/2 a_{n+1}
  // loses with the element's force (dt/2 T/m per node, O(dt)): measured 17 % of the released energy
  // here, where the break happens at 0.2 % strain, and it does not grow afterwards.
  EXPECT_LT(std::abs(b.balanceError() - errBefore), 0.25 * ev.energy);
  for (int k = 0; k < 2000; ++k) e.step(dt);
  const Real later = e.dynamics().energy().balanceError();
  EXPECT_LT(std::abs(later - b.balanceError()), 0.05 * ev.energy);
}

// Weibull strengths: same seed, same strengths; the sample mean is the failure strain and the
// spread follows the modulus: CV = sqrt(G(1+2/m) - G(1+1/m)^2) / G(1+1/m).
TEST(Breakage, WeibullStrengthsAreSeededWithTheGivenMeanAndSpread) {
  Fabric f;
  for (int y = 0; y < 4000; ++y) f.addYarn({Vec3(0, y * 1e-3, 0), Vec3(1e-3, y * 1e-3, 0)}, km2Material(), YarnSection());
  BreakageParams p;
  p.enabled = true, p.threshold = 0.04, p.weibullModulus = 8, p.seed = 42;
  Breakage a, b, c;
  a.configure(f, p);
  b.configure(f, p);
  p.seed = 43;
  c.configure(f, p);
  EXPECT_EQ(a.yarnStrength(), b.yarnStrength());
  EXPECT_NE(a.yarnStrength(), c.yarnStrength());
  Real mean = 0, sq = 0;
  for (Real s : a.yarnStrength()) mean += s, sq += s * s;
  mean /= 4000;
  const Real sd = std::sqrt(sq / 4000 - mean * mean);
  const Real g1 = std::tgamma(1 + 1.0 / 8), g2 = std::tgamma(1 + 2.0 / 8);
  const Real cv = std::sqrt(g2 - g1 * g1) / g1;
  EXPECT_NEAR(mean, 0.04, 4 * 0.04 * cv / std::sqrt(4000.0));  // 4 standard errors
  EXPECT_NEAR(sd / mean, cv, 0.1 * cv);
}

TEST(Breakage, BadParametersNameThemselves) {
  Fabric f = straightChain(4, 1e-3);
  ChainDynamics d(f);
  BreakageParams p;
  p.enabled = true;
  p.threshold = 20;
  EXPECT_EQ(parameterOf([&] { d.configureBreakage(p); }), "break_strain");
  p.threshold = 0.05, p.filterLength = NAN;
  EXPECT_EQ(parameterOf([&] { d.configureBreakage(p); }), "break_filter");
  p.filterLength = -200;
  EXPECT_EQ(parameterOf([&] { d.configureBreakage(p); }), "break_filter");
  p.filterLength = 0, p.weibullModulus = 0.5;
  EXPECT_EQ(parameterOf([&] { d.configureBreakage(p); }), "weibull_m");
}

// Impulses between a free yarn and a body conserve the total momentum (the springs do too), step
// by step: a box hit face on; a sphere hit off the yarn's axis, which does not turn (its impulses
// pass through its centre); a box hit off centre, which must turn.
TEST(RigidBodies, ExchangeMomentumExactlyAndTurnWithTheirInertia) {
  for (int shape = 0; shape < 3; ++shape) {
    auto e = yarnEngine(0.0, false);
    const Real h = 0.5e-3;
    if (shape == 0) e->collisions()->bodies.push_back(cube(h, 1e-5, Vec3(0, 0, 1e-4 + h + 2e-6), Vec3(0, 0, -50)));
    if (shape == 1) e->collisions()->bodies.push_back(ball(h, 1e-5, Vec3(0, 0.3e-3, 1e-4 + h + 2e-6), Vec3(0, 0, -50)));
    if (shape == 2) e->collisions()->bodies.push_back(cube(h, 1e-5, Vec3(0, 0.4e-3, 1e-4 + h + 2e-6), Vec3(0, 0, -50)));
    const Vec3 p0 = momentum(*e);
    const Real dt = 0.5 * e->criticalDt();
    long rows = 0;
    for (int k = 0; k < 400; ++k) {  // 40 CPs: short in every build
      e->step(dt);
      rows += e->collisions()->stats.impulses.rows;
      EXPECT_LT((momentum(*e) - p0).norm(), 1e-12 * p0.norm()) << "shape " << shape << " step " << k;
    }
    EXPECT_GT(rows, 0) << "shape " << shape;
    const RigidBody& b = e->collisions()->bodies[0];
    EXPECT_GT(b.vel.z(), -50) << "the yarn slows the body";
    if (shape == 2) {
      EXPECT_GT(std::abs(b.angVel.x()), 1.0) << "an off-centre hit turns the box";
    }
    if (shape == 1) {
      EXPECT_LT(b.angVel.norm(), 1e-9) << "a frictionless sphere does not turn";
    }
  }
}

// A 1 mm cube or sphere at 1000 m/s onto a yarn clamped at its ends: it travels 16 um per step,
// the yarn's 0.2 mm diameter in 13 steps. With e = 0 the yarn is carried along in front of the body:
// the node under it stays below the body's face by the yarn's radius, to within 5 um (5 % of the
// radius: the sphere's contacts are measured on each CP's straight axis while the yarn wraps it).
TEST(RigidBodies, NoTunnellingAt1000MetresPerSecond) {
  for (int shape = 0; shape < 2; ++shape) {
    auto e = yarnEngine(0.0, true);
    const Real h = 0.5e-3;
    const Vec3 start(0, 0, 1e-4 + h + 5e-6);
    e->collisions()->bodies.push_back(shape == 0 ? cube(h, 1e-3, start, Vec3(0, 0, -1000))
                                                 : ball(h, 1e-3, start, Vec3(0, 0, -1000)));
    const Real dt = 0.7 * e->criticalDt();
    for (int k = 0; k < 300; ++k) {
      e->step(dt);
      const RigidBody& b = e->collisions()->bodies[0];
      const Vec3& x = e->fabric().pos[20];  // the node under the body's centre
      // Below the body by its section's half-thickness, which the body flattens (up to the MCD).
      const Real half = semiAxes(1e-4, e->fabric().secFlat[20], e->collisions()->params().rule).b;
      EXPECT_GE(half, 1e-4 * (1 - e->collisions()->params().mcd) - 1e-15);
      EXPECT_LT(x.z(), b.pos.z() - h - half + 5e-6) << "shape " << shape << " step " << k;
    }
    EXPECT_LT(e->fabric().pos[20].z(), -1e-3) << "the yarn is carried along";
  }
}

// Head-on with e = 1 a body and one free CP exchange velocities as two elastic masses do:
// kinetic energy is kept to 1e-9 and the body's velocity follows (m1 - m2)/(m1 + m2) v.
TEST(RigidBodies, ElasticImpactKeepsKineticEnergy) {
  Fabric f;
  f.addYarn({Vec3(-0.5e-3, 0, 0), Vec3(0.5e-3, 0, 0)}, km2Material(), roundSection(1e-4));
  FabricEngine e(std::move(f));
  ContactParams p;
  p.restitution = 1;
  p.positionCorrection = 0;
  p.tolerance = 1e-12;  // the gap model holds the CP at both ends: two rows, solved to this [m/s]
  p.solverTolerance = 0;
  e.enableCollisions(p);
  const Real mCP = e.fabric().mass[0] + e.fabric().mass[1], M = 3 * mCP, h = 0.2e-3;
  e.collisions()->bodies.push_back(cube(h, M, Vec3(0, 0, 1e-4 + h + 1e-6), Vec3(0, 0, -10)));
  const Real ke0 = 0.5 * M * 100;
  const Real dt = 0.5 * e.criticalDt();
  for (int k = 0; k < 200; ++k) e.step(dt);
  const RigidBody& b = e.collisions()->bodies[0];
  Real ke = b.kineticEnergy();
  for (Index i = 0; i < 2; ++i) ke += 0.5 * e.fabric().mass[i] * e.fabric().vel[i].squaredNorm();
  EXPECT_NEAR(ke / ke0, 1.0, 1e-9);
  EXPECT_NEAR(b.vel.z(), (M - mCP) / (M + mCP) * -10, 1e-9 * 10);
}

// The body's work on the fabric is booked as work, its dissipation as contact: with e = 0 the
// fabric's books balance to the integrator's accuracy and the dissipated energy is what the two
// sides lost together.
TEST(RigidBodies, BodyWorkAndDissipationAreBookedApart) {
  auto e = yarnEngine(0.0, true);
  const Real h = 0.5e-3;
  e->collisions()->bodies.push_back(cube(h, 1e-4, Vec3(0, 0, 1e-4 + h + 2e-6), Vec3(0, 0, -100)));
  const Real keBody0 = e->collisions()->bodies[0].kineticEnergy();
  const Real dt = 0.7 * e->criticalDt();
  for (int k = 0; k < 600; ++k) e->step(dt);
  const EnergyBooks b = e->dynamics().energy();
  const Real keBody = e->collisions()->bodies[0].kineticEnergy();
  EXPECT_NEAR(b.bodyWork, keBody0 - keBody, 1e-12 * keBody0);
  EXPECT_GT(b.contact, 0);  // e = 0 dissipates
  EXPECT_LT(std::abs(b.balanceError()), 0.01 * b.bodyWork);
}

// With restitution the books still balance. The restitution pass acts after the drift, so its dv
// first shows in the next step's kinetic energy; booked at v_n (as the pass before the drift is) the
// books lost m dv . a dt a step, an error halving with dt: -1.57 % and -0.79 % of the body's work
// here at 0.6 and 0.3 dt_crit (measured), -1.6 % of the impact energy in the 12.7 mm ballistic ply at
// e = 0.5. Booked at v_{n+1/2} + (dt/2) a_n: 1.2e-5 and 5.0e-6. A kinematic cube drives into a
// clamped yarn at 20 m/s for 20 us, so the yarn's tension pulls it back into the cube and the
// restitution bounces it at most steps.
TEST(RigidBodies, RestitutionKeepsTheBooks) {
  const auto balance = [](Real safety) {
    auto e = yarnEngine(0.5, true);
    const Real h = 0.5e-3;
    e->collisions()->bodies.push_back(cube(h, 0, Vec3(0, 0, 1e-4 + h), Vec3(0, 0, -20)));
    const Real dt = safety * e->criticalDt();
    const int steps = static_cast<int>(std::lround(20e-6 / dt));
    for (int k = 0; k < steps; ++k) e->step(dt);
    const EnergyBooks b = e->dynamics().energy();
    EXPECT_GT(b.contactInput, 0.5 * b.work) << "the restitution gave back energy";
    return b.balanceError() / b.work;
  };
  for (const Real safety : {0.6, 0.3}) EXPECT_LT(std::abs(balance(safety)), 1e-4) << "at " << safety << " dt_crit";
}

TEST(RigidBodies, BadBodiesNameTheirField) {
  RigidBody b = cube(1e-3, 1e-3, Vec3::Zero(), Vec3::Zero());
  b.mass = -1;
  EXPECT_EQ(parameterOf([&] { b.validate(); }), "mass");
  b.mass = 1e-3, b.vel = Vec3(NAN, 0, 0);
  EXPECT_EQ(parameterOf([&] { b.validate(); }), "velocity");
  b.vel.setZero(), b.parts[0].halfSize.x() = 0;
  EXPECT_EQ(parameterOf([&] { b.validate(); }), "extents");
  b.parts.clear();
  EXPECT_EQ(parameterOf([&] { b.validate(); }), "parts");
}

// A body placed across the yarn overlaps it; one above it does not.
TEST(RigidBodies, OverlapAtTheStartIsMeasured) {
  auto e = yarnEngine(0.0, true);
  e->collisions()->bodies.push_back(cube(0.5e-3, 1e-3, Vec3(0, 0, 0.3e-3), Vec3::Zero()));
  e->collisions()->bodies.push_back(ball(0.5e-3, 1e-3, Vec3(0, 0, 0.7e-3), Vec3::Zero()));
  EXPECT_NEAR(e->collisions()->bodyOverlap(e->fabric(), 0), 0.1e-3 + 0.1e-3 - 0.3e-3 + 0.5e-3 - 1e-6 + 1e-6 - 0.1e-3, 2e-6);
  EXPECT_LT(e->collisions()->bodyOverlap(e->fabric(), 1), 0);
}
