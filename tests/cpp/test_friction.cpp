// Coulomb friction in the impulse rows and its own energy book (EnergyBooks::friction): a CP that
// lands obliquely on a still body or on a fixed crossing yarn, where the closed form is that of a
// block on a floor. The normal impulses take all the approach, J_n = m v_z0 in total; while the CP
// slides the tangential impulse is mu J_n, so v_y = v_y0 - mu v_z0, and friction's book is the lost
// tangential kinetic energy, 1/2 m (v_y0^2 - v_y^2) (all of it, 1/2 m v_y0^2, when it sticks:
// mu v_z0 >= v_y0); the contact book keeps the normal part, 1/2 m v_z0^2.
#include "body_util.hpp"
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "fabric/StateIO.hpp"
#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>

using namespace woven;
using namespace woven_test;

namespace {

constexpr Real kR = 1e-4;  // yarn radius [m]

YarnSection round(Real r) {
  YarnSection s;
  s.width = s.thickness = 2 * r;
  return s;
}

struct Landing {
  Real vy = 0, contact = 0, friction = 0, balance = 0, mass = 0, projection = 0;
  EnergyBooks books;
};

// One free CP along x (1 mm, its nodes at the same velocity (0, vy0, -vz0)) lands on a still
// kinematic cube (onBody) or on a fixed yarn along y under its middle; 30 steps of 0.5 dt_crit.
Landing land(bool onBody, Real mu, Real muBody, Real vy0, Real vz0, FabricEngine** keep = nullptr, Real bodyMass = 0) {
  Fabric f;
  f.addYarn({Vec3(-0.5e-3, 0, 0), Vec3(0.5e-3, 0, 0)}, km2Material(), round(kR));
  if (!onBody) {
    Vec3Array pts;
    for (int i = 0; i <= 8; ++i) pts.push_back(Vec3(0, (i - 4) * 0.5e-3, -2 * kR - 1e-6));
    f.addYarn(pts, km2Material(), round(kR));
  }
  static std::unique_ptr<FabricEngine> held;
  held = std::make_unique<FabricEngine>(std::move(f));
  FabricEngine& e = *held;
  if (!onBody)
    for (Index i = 2; i < e.fabric().nNodes(); ++i) e.dynamics().fix(i);
  ContactParams p;
  p.friction = mu, p.bodyFriction = muBody, p.positionCorrection = 0, p.tolerance = 1e-12;
  p.solverTolerance = 0;
  e.enableCollisions(p);
  const Real h = 1e-3;
  if (onBody) e.collisions()->bodies.push_back(cube(h, bodyMass, Vec3(0, 0, -kR - h - 1e-6), Vec3::Zero()));
  for (Index i = 0; i < 2; ++i) e.fabric().vel[i] = Vec3(0, vy0, -vz0);
  const Real dt = 0.5 * e.criticalDt();
  for (int k = 0; k < 30; ++k) e.step(dt);
  Landing r;
  r.books = e.dynamics().energy();
  r.vy = 0.5 * (e.fabric().vel[0].y() + e.fabric().vel[1].y());
  r.contact = r.books.contact, r.friction = r.books.friction, r.balance = r.books.balanceError();
  r.projection = r.books.projection;
  r.mass = e.fabric().mass[0] + e.fabric().mass[1];
  if (keep) *keep = &e;
  return r;
}

}  // namespace

TEST(Friction, SlidingCPLosesMuTimesTheNormalImpulseAndFrictionBooksItsWork) {
  const Real vy0 = 5, vz0 = 2, mu = 0.3;
  for (int onBody = 0; onBody < 2; ++onBody) {
    // The other pair's coefficient is set to something else: each row takes its own.
    const Landing r = onBody ? land(true, 0.9, mu, vy0, vz0) : land(false, mu, 0.9, vy0, vz0);
    const Real vy = vy0 - mu * vz0;
    EXPECT_NEAR(r.vy, vy, 1e-9 * vy0) << "body " << onBody;
    EXPECT_NEAR(r.friction, 0.5 * r.mass * (vy0 * vy0 - vy * vy), 1e-9 * 0.5 * r.mass * vy0 * vy0) << "body " << onBody;
    EXPECT_NEAR(r.contact, 0.5 * r.mass * vz0 * vz0, 1e-9 * 0.5 * r.mass * vy0 * vy0) << "body " << onBody;
    EXPECT_NEAR(r.balance, 0, 1e-12 * 0.5 * r.mass * vy0 * vy0) << "body " << onBody;
  }
}

TEST(Friction, StickingCPLosesAllItsSlipToFriction) {
  const Real vy0 = 1, vz0 = 2, mu = 1.5;  // mu vz0 = 3 > vy0: the cone holds it
  for (int onBody = 0; onBody < 2; ++onBody) {
    const Landing r = onBody ? land(true, 0, mu, vy0, vz0) : land(false, mu, 0, vy0, vz0);
    EXPECT_NEAR(r.vy, 0, 1e-9 * vy0) << "body " << onBody;
    EXPECT_NEAR(r.friction, 0.5 * r.mass * vy0 * vy0, 1e-9 * 0.5 * r.mass * vy0 * vy0) << "body " << onBody;
    EXPECT_NEAR(r.contact, 0.5 * r.mass * vz0 * vz0, 1e-9 * 0.5 * r.mass * vz0 * vz0) << "body " << onBody;
  }
}

// Coefficient 0 on the pair that touches: no tangential impulse, an empty friction book.
TEST(Friction, EachPairTakesItsOwnCoefficient) {
  const Landing onBody = land(true, 0.8, 0, 5, 2), onYarn = land(false, 0, 0.8, 5, 2);
  EXPECT_EQ(onBody.vy, 5.0);
  EXPECT_EQ(onBody.friction, 0.0);
  EXPECT_EQ(onYarn.vy, 5.0);
  EXPECT_EQ(onYarn.friction, 0.0);
}

// On a free (dynamic) cube the tangential impulse also turns it (its arm runs along the normal):
// no closed form for the split, but the books close to rounding (the body's kinetic energy is its
// work on the fabric, the rest the two contact books), friction took a share, and momentum is kept.
TEST(Friction, BooksCloseOnADynamicBody) {
  FabricEngine* e = nullptr;
  const Real mCP = 2 * 0.5 * 1e-3 * km2Material().rho * km2Material().area;  // the CP's two half masses
  const Landing r = land(true, 0, 0.5, 5, 2, &e, 10 * mCP);
  const Real ke0 = 0.5 * r.mass * (25 + 4);
  const RigidBody& b = e->collisions()->bodies[0];
  EXPECT_GT(r.friction, 0.01 * ke0);
  EXPECT_GT(b.angVel.norm(), 0) << "the tangential impulse turns the cube";
  EXPECT_NEAR(r.balance, 0, 1e-12 * ke0);
  EXPECT_NEAR(r.books.bodyWork, -b.kineticEnergy(), 1e-12 * ke0);
  Vec3 p = b.mass * b.vel;
  for (Index i = 0; i < 2; ++i) p += e->fabric().mass[i] * e->fabric().vel[i];
  EXPECT_LT((p - r.mass * Vec3(0, 5, -2)).norm(), 1e-12 * r.mass * 5);
}

// The friction book travels with a state file (format version 4).
TEST(Friction, BookIsSavedAndLoaded) {
  FabricEngine* e = nullptr;
  const Landing r = land(true, 0, 0.3, 5, 2, &e);
  ASSERT_GT(r.friction, 0);
  const std::string path = ::testing::TempDir() + "woven_friction.state";
  e->saveState(path);
  const Real before = e->dynamics().energy().friction;
  e->step(0.5 * e->criticalDt());  // moves the books on, then back
  e->setState(loadState(path, e->fabric().nNodes()));
  EXPECT_EQ(e->dynamics().energy().friction, before);
  std::remove(path.c_str());
}

TEST(Friction, CoefficientsOutOfRangeNameThemselves) {
  ContactParams p;
  p.friction = 2.5;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "friction");
  p.friction = 0, p.bodyFriction = -0.1;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "body_friction");
  p.bodyFriction = NAN;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "body_friction");
  p.bodyFriction = 0.2, p.response = Response::Penalty;  // friction acts in the impulse rows only
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "body_friction");
}
