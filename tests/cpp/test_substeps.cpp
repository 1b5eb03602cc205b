// Spring substeps (FabricEngine::setSubsteps, multiple time stepping): without collisions they are
// that many plain steps bit for bit; with a body striking a yarn the contacts found once per step
// and solved every substep still conserve momentum exactly, keep the body out of the yarn, close
// the energy books, and give the closed-form elastic exchange; bad counts and the laws that cannot
// substep are refused before anything moves.
#include "body_util.hpp"
#include "chain_util.hpp"
#include "yarn_util.hpp"
#include "engine/FabricEngine.hpp"
#include <gtest/gtest.h>
#include <cmath>

using namespace woven;
using namespace woven_test;

namespace {

// A straight round yarn (r = 0.1 mm) of 40 CPs of 0.25 mm along x, its nodes given a transverse
// wave (a plucked string) so that the springs work.
Fabric pluckedYarn() {
  Vec3Array pts;
  for (int i = 0; i <= 40; ++i) pts.push_back(Vec3((i - 20) * 0.25e-3, 0, 0));
  Fabric f;
  f.addYarn(pts, km2Material(), roundSection(1e-4));
  for (Index i = 0; i < f.nNodes(); ++i) f.vel[i] = Vec3(0, 0, 5 * std::sin(0.3 * i));
  return f;
}

std::unique_ptr<FabricEngine> yarnWithCollisions(Real restitution, bool clampEnds, int substeps) {
  auto e = yarnEngine(restitution, clampEnds);
  e->setSubsteps(substeps);
  return e;
}

}  // namespace

// m substeps of a step of dt are m plain steps of dt / m: the same arithmetic, the same bits.
TEST(Substeps, WithoutCollisionsAreThatManyPlainStepsBitForBit) {
  FabricEngine a(pluckedYarn()), b(pluckedYarn());
  a.setSubsteps(4);
  const Real h = 0.7 * a.criticalDt();
  EXPECT_EQ(a.maxStep(), 4 * a.criticalDt());
  for (int k = 0; k < 50; ++k) a.step(4 * h);
  for (int k = 0; k < 200; ++k) b.step(h);
  EXPECT_EQ(a.dynamics().stepCount(), b.dynamics().stepCount());
  for (Index i = 0; i < a.fabric().nNodes(); ++i) {
    EXPECT_EQ(a.fabric().pos[i], b.fabric().pos[i]) << "node " << i;
    EXPECT_EQ(a.fabric().vel[i], b.fabric().vel[i]) << "node " << i;
  }
}

// A cube at 100 m/s onto a free yarn, contacts once per 4 spring substeps: impulses and springs are
// internal, so the total momentum holds to rounding at every step; the yarn slows the cube.
TEST(Substeps, BodyImpactConservesMomentumExactly) {
  auto e = yarnWithCollisions(0.0, false, 4);
  const Real h = 0.5e-3;
  e->collisions()->bodies.push_back(cube(h, 1e-5, Vec3(0, 0, 1e-4 + h + 2e-6), Vec3(0, 0, -100)));
  const Vec3 p0 = momentum(*e);
  const Real dt = 4 * 0.7 * e->criticalDt();
  long rows = 0;
  for (int k = 0; k < 100; ++k) {
    e->step(dt);
    rows += e->collisions()->stats.impulses.rows;
    EXPECT_LT((momentum(*e) - p0).norm(), 1e-12 * p0.norm()) << "step " << k;
  }
  EXPECT_GT(rows, 0);
  EXPECT_GT(e->collisions()->bodies[0].vel.z(), -100) << "the yarn slows the body";
}

// The clamped yarn under a 1 mm cube at 500 m/s with 4 substeps: the node under the cube stays
// below its face by the section's half-thickness (within 5 um, as one substep per contact pass holds
// it in RigidBodies.NoTunnellingAt1000MetresPerSecond), and the books balance within 1 % of the
// body's work on the fabric (e = 0: the contacts dissipate). 150 steps carry the yarn 6 mm, far past
// any failure strain (nothing breaks here), its tension pulling it back into the cube between the
// passes: the rows solved again every substep hold it. With the rows of the pass start only, the
// node went 3-10 um into the cube from about 18 % strain on and the yarn slipped round it past 50 %.
TEST(Substeps, ClampedYarnIsCarriedAheadOfTheBodyAndTheBooksClose) {
  auto e = yarnWithCollisions(0.0, true, 4);
  const Real h = 0.5e-3;
  e->collisions()->bodies.push_back(cube(h, 1e-3, Vec3(0, 0, 1e-4 + h + 5e-6), Vec3(0, 0, -500)));
  const Real dt = 4 * 0.7 * e->criticalDt();
  for (int k = 0; k < 150; ++k) {
    e->step(dt);
    const RigidBody& b = e->collisions()->bodies[0];
    const Real half = semiAxes(1e-4, e->fabric().secFlat[20], e->collisions()->params().rule).b;
    EXPECT_LT(e->fabric().pos[20].z(), b.pos.z() - h - half + 5e-6) << "step " << k;
  }
  EXPECT_LT(e->fabric().pos[20].z(), -5e-3) << "the yarn is carried along";
  const EnergyBooks books = e->dynamics().energy();
  EXPECT_GT(books.contact, 0);
  EXPECT_LT(std::abs(books.balanceError()), 0.01 * books.bodyWork);
}

// Head-on with e = 1 a body and one free CP exchange velocities as two elastic masses do, with the
// CP's spring substepped: (M - m) / (M + m) v for the body, kinetic energy kept to 1e-9.
TEST(Substeps, ElasticImpactGivesTheTwoMassExchange) {
  Fabric f;
  f.addYarn({Vec3(-0.5e-3, 0, 0), Vec3(0.5e-3, 0, 0)}, km2Material(), roundSection(1e-4));
  FabricEngine e(std::move(f));
  ContactParams p;
  p.restitution = 1;
  p.positionCorrection = 0;
  p.tolerance = 1e-12, p.solverTolerance = 0;
  e.enableCollisions(p);
  e.setSubsteps(3);
  const Real mCP = e.fabric().mass[0] + e.fabric().mass[1], M = 3 * mCP, h = 0.2e-3;
  e.collisions()->bodies.push_back(cube(h, M, Vec3(0, 0, 1e-4 + h + 1e-6), Vec3(0, 0, -10)));
  const Real ke0 = 0.5 * M * 100;
  const Real dt = 3 * 0.5 * e.criticalDt();
  for (int k = 0; k < 70; ++k) e.step(dt);
  const RigidBody& b = e.collisions()->bodies[0];
  Real ke = b.kineticEnergy();
  for (Index i = 0; i < 2; ++i) ke += 0.5 * e.fabric().mass[i] * e.fabric().vel[i].squaredNorm();
  EXPECT_NEAR(ke / ke0, 1.0, 1e-9);
  EXPECT_NEAR(b.vel.z(), (M - mCP) / (M + mCP) * -10, 1e-9 * 10);
}

TEST(Substeps, BadCountsStepsAndForceLawsAreRefused) {
  FabricEngine e(pluckedYarn());
  EXPECT_EQ(parameterOf([&] { e.setSubsteps(0); }), "substeps");
  EXPECT_EQ(parameterOf([&] { e.setSubsteps(65); }), "substeps");
  EXPECT_EQ(e.substeps(), 1);
  e.setSubsteps(2);
  EXPECT_EQ(parameterOf([&] { e.step(2.01 * e.criticalDt()); }), "dt");
  EXPECT_EQ(e.dynamics().stepCount(), 0) << "nothing moved";
  e.step(2 * e.criticalDt());
  EXPECT_EQ(e.dynamics().stepCount(), 2);
  // Penalty forces and section springs would act over one substep of the step: refused both ways.
  ContactParams penalty;
  penalty.response = Response::Penalty;
  EXPECT_EQ(parameterOf([&] { e.enableCollisions(penalty); }), "substeps");
  EXPECT_EQ(e.collisions(), nullptr);
  e.setSubsteps(1);
  e.enableCollisions(penalty);
  EXPECT_EQ(parameterOf([&] { e.setSubsteps(2); }), "substeps");
  EXPECT_EQ(e.substeps(), 1);
  ContactParams springs;
  springs.flattening = Flattening::Springs;
  e.enableCollisions(springs);
  EXPECT_EQ(parameterOf([&] { e.setSubsteps(3); }), "substeps");
  ContactParams paper;  // its contacts are not measured again between passes
  paper.model = ContactModel::Paper;
  e.enableCollisions(paper);
  EXPECT_EQ(parameterOf([&] { e.setSubsteps(3); }), "substeps");
}
