// The energy books under gravity (docs/collisions.md "Energy books"). The impulse law books
// an impulse's energy at the synchronised velocity v_n = v_{n+1/2} - dt/2 a_n. With the forces' part
// of a_n alone, a contact that holds a node up against gravity booked (m/2)(g dt)^2 of dissipation
// every step that the motion never had; a body the host (YADE) kicks with gravity likewise booked
// (M/2)(g dt)^2 of work on the fabric a step. The oracles are independent of the books: the fabric's
// gravity work from its own positions, the body's energy from the host's side (its kinetic energy at
// the synchronised velocity and the work of gravity along its path).
#include "body_util.hpp"
#include "chain_util.hpp"
#include "yarn_util.hpp"
#include "engine/FabricEngine.hpp"
#include <gtest/gtest.h>
#include <cmath>
#include <memory>

using namespace woven;
using namespace woven_test;

namespace {

const Vec3 kGravity(0, 0, -9.81);

// A layer of straight round yarns (r = 0.1 mm, 12 CPs of 0.25 mm along x, `pitch` apart, damping
// 0.1) with collisions, under gravity. taut: the ends pulled out by 0.1 % and clamped (4.2 N each).
std::unique_ptr<FabricEngine> layer(int yarns, Real pitch, bool taut) {
  Fabric f;
  for (int y = 0; y < yarns; ++y) {
    Vec3Array pts;
    for (int i = 0; i <= 12; ++i) pts.push_back(Vec3(i * 0.25e-3, y * pitch, 0));
    f.addYarn(pts, km2Material(0.1), roundSection(1e-4));
  }
  auto e = std::make_unique<FabricEngine>(std::move(f));
  if (taut)
    for (const Yarn& y : e->fabric().yarns) {
      const Index a = y.firstNode, b = y.firstNode + y.nNodes - 1;
      e->fabric().pos[a].x() -= 1.5e-6, e->fabric().pos[b].x() += 1.5e-6;  // before the books start: initial energy
      e->dynamics().fix(a), e->dynamics().fix(b);
    }
  e->enableCollisions(ContactParams{});
  e->dynamics().setBodyAcceleration(kGravity);
  return e;
}

// The fabric's potential energy in gravity [J]: -sum m g.x over the free nodes.
Real potential(const FabricEngine& e) {
  const Fabric& f = e.fabric();
  Real u = 0;
  for (Index i = 0; i < f.nNodes(); ++i)
    if (f.invMass[i] > 0) u -= f.mass[i] * kGravity.dot(f.pos[i]);
  return u;
}

}  // namespace

// A layer of six straight round yarns (r = 0.1 mm, 12 CPs of 0.25 mm along x, 1 mm apart, damping
// 0.1, every node free) dropped from 3 um onto a fixed box: it lands at 0.8 ms and rests there for
// the rest of the 1e5 steps (3 ms). The books close to 1e-6 of the potential energy the layer turned
// over, and their gravity work is that potential energy (from the positions). Without the gravity term
// the resting contacts' rows booked (m/2)(g dt)^2 a step: the balance ended 1e-4 of the turnover off,
// growing with every step. (A plain weave collapses onto a flat box, having no bending stiffness:
// its crossings fall through tens of um and its tension-only yarns jolt taut and slack, which leaves
// the leapfrog's own O(dt^2) energy error, ~1e-4 of the turnover, in the balance, unrelated to the
// books; the layer lands without it.)
TEST(GravityBooks, FabricRestingOnABoxKeepsTheBooks) {
  auto engine = layer(6, 1e-3, false);
  FabricEngine& e = *engine;
  // the box: fixed (mass 0) under the whole layer, its top 3 um below the yarns' round sections
  // (sanitizer builds: a tenth of the run, the layer 20 nm above the box, so that it lands at 60 us
  // and rests for the rest)
  const Real drop = kSlowBuild ? 20e-9 : 3e-6;
  e.collisions()->bodies.push_back(cube(5e-3, 0.0, Vec3(1.5e-3, 2.5e-3, -1e-4 - drop - 5e-3), Vec3::Zero()));
  const Real u0 = potential(e);
  const Real dt = 0.7 * e.criticalDt();
  const long steps = runLength(100000, 10);
  long resting = 0;
  for (long s = 0; s < steps; ++s) {
    e.step(dt);
    if (e.collisions()->stats.bodyContacts > 0) ++resting;
  }
  const EnergyBooks& b = e.dynamics().energy();
  const Real turnover = u0 - potential(e);  // what gravity gave over the run [J]
  EXPECT_GT(resting, steps / 2) << "the layer rests on the box for most of the run";
  EXPECT_GT(turnover, 0) << "it fell";
  EXPECT_NEAR(b.work, turnover, 1e-9 * turnover) << "gravity's work in the books is the potential energy turned over";
  EXPECT_LT(std::abs(b.balanceError()), 1e-6 * turnover)
      << "balance " << b.balanceError() << " J of " << turnover << " J turned over; contact book " << b.contact << " J";
  EXPECT_LT(b.kinetic, 1e-6 * turnover) << "at rest by the end";
}

// A 1 g cube resting on a taut layer (four yarns 0.4 mm apart, clamped at 4.2 N each) under gravity;
// the host (here the test, as YADE's NewtonIntegrator: v += g dt, x += v dt, then the woven step with
// the pose taken back) kicks it. It lands from 20 nm and rides the yarns, which give ~1 um under
// it. The work the books say the cube did on the fabric must be what the cube lost: the work of
// gravity along its path less its kinetic energy gain (both at the synchronised velocity, as the books
// count the fabric's nodes), to 1e-6 of the potential energy it turned over. Counted at the half-step velocity, the
// books counted the cube's energy at its half-step velocities: (M/2)(g dt)^2 of work a step that it
// never did. (tests/python/test_gravity_books.py: the same with YADE's own NewtonIntegrator.)
TEST(GravityBooks, BodyRestingOnAFabricKeepsTheBooks) {
  auto engine = layer(4, 0.4e-3, true);
  FabricEngine& e = *engine;
  const Real M = 1e-3;
  // 20 nm above the yarns' tops (round sections of 0.1 mm), over the middle two yarns
  e.collisions()->bodies.push_back(cube(0.5e-3, M, Vec3(1.5e-3, 0.6e-3, 1e-4 + 2e-8 + 0.5e-3), Vec3::Zero()));
  const Real dt = 0.7 * e.criticalDt();
  const long steps = runLength(100000, 10);  // it lands at ~64 us (2 800 steps)
  RigidBody& cube = e.collisions()->bodies[0];
  // the host's side: its velocity after the woven step (what it integrates from), the work of gravity
  Vec3 vHost = cube.vel;
  const Real ke0 = 0.5 * M * (vHost + 0.5 * dt * kGravity).squaredNorm();  // synchronised, at step 0
  Real gravityWork = 0;
  long resting = 0;
  for (long s = 0; s < steps; ++s) {
    // NewtonIntegrator: kick, drift; the woven adapter takes the pose back to x_n (rewind)
    const Vec3 vHalf = vHost + dt * kGravity;
    const Vec3 x0 = cube.pos;
    cube.setHostState(x0 + dt * vHalf, cube.ori, vHalf, cube.angVel, dt, true);
    e.step(dt);
    gravityWork += M * kGravity.dot(cube.pos - x0);
    vHost = cube.vel;
    if (e.collisions()->stats.bodyContacts > 0) ++resting;
  }
  const Vec3 vSync = vHost + 0.5 * dt * kGravity;  // the next kick's first half
  const Real rotation = cube.kineticEnergy() - 0.5 * M * cube.vel.squaredNorm();  // no host kick turns it
  const Real lost = gravityWork - (0.5 * M * vSync.squaredNorm() + rotation - ke0);
  const EnergyBooks& b = e.dynamics().energy();
  EXPECT_GT(resting, steps / 2) << "the cube rests on the fabric for most of the run";
  EXPECT_GT(gravityWork, 0) << "it came down";
  EXPECT_GT(b.bodyWork, 0.1 * gravityWork) << "onto the yarns, which took what gravity gave it";
  EXPECT_NEAR(b.bodyWork, lost, 1e-6 * gravityWork)
      << "body work in the books " << b.bodyWork << " J, the cube lost " << lost << " J of " << gravityWork << " J";
  // (The fabric's own balance does not see this: the body's work is booked as work and as contact
  // take alike. The cube's landing sets the clamped yarns ringing, whose leapfrog error, ~3e-4 of the
  // cube's turnover, is the integrator's, not the books'.)
}
