// The check before the rows (PositionProjection with checkDepth, CollisionStage::checkOverlaps): a
// contact still overlapping after the flattening passes by more than projection_check is projected
// out with no allowance; shallower ones are left; the energy of its moves is booked with the drift
// term of a move made before the drift; its moves count against the travel of the projection after
// the drift.
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "geom/GapFunction.hpp"
#include "law/PositionProjection.hpp"
#include <gtest/gtest.h>
#include <cmath>

using namespace woven;
using namespace woven_test;

namespace {

constexpr Real kR = 5e-5;  // yarn radius [m]: 0.1 mm thick

YarnSection round(Real r) {
  YarnSection s;
  s.width = s.thickness = 2 * r;
  return s;
}

// Yarn A along x (nodes 0-2), yarn B along y (nodes 3-5) above it, their axes 2 kR - overlap apart
// where A's first CP (s = 0.75) crosses B's first CP (s = 0.75). Springs loaded (rest lengths 1 %
// short, yarns not tension-only) so that moving a node changes their forces.
Fabric crossing(Real overlap) {
  const Real L = 0.4e-3, z = 2 * kR - overlap;
  Fabric f;
  f.addYarn({Vec3(-0.75 * L, 0, 0), Vec3(0.25 * L, 0, 0), Vec3(1.25 * L, 0, 0)}, km2Material(0, false), round(kR));
  f.addYarn({Vec3(0, -0.75 * L, z), Vec3(0, 0.25 * L, z), Vec3(0, 1.25 * L, z)}, km2Material(0, false), round(kR));
  for (Index e = 0; e < f.nElems(); ++e) {
    f.restLength[e] *= 0.99;
    f.stiffness[e] = f.materials[0].E * f.materials[0].area / f.restLength[e];
  }
  return f;
}

CPContact measured(const Fabric& f) {
  CPContact c[2];
  EXPECT_EQ(pairGaps(f, 0, 2, false, SectionRule::ConstantArea, nullptr, c), 1);
  return c[0];
}

// Hooke's law of CP e at positions x (the test's own, from the material's E A / l0).
Real energyOf(const Fabric& f, const Vec3Array& x, Index e) {
  const Real K = f.materials[0].E * f.materials[0].area / f.restLength[e];
  const Real d = (x[f.elem0[e] + 1] - x[f.elem0[e]]).norm() - f.restLength[e];
  return 0.5 * K * d * d;
}
Vec3 forceOf(const Fabric& f, const Vec3Array& x, Index e) {  // on the CP's first node
  const Real K = f.materials[0].E * f.materials[0].area / f.restLength[e];
  const Vec3 d = x[f.elem0[e] + 1] - x[f.elem0[e]];
  return K * (d.norm() - f.restLength[e]) / d.norm() * d;
}

}  // namespace

// The projection after the drift leaves an overlap that the allowance covers; the check (run after
// the flattening, when the allowance has had its turn) takes it out to the slop, and books
// dU - dt/2 dF . (v_i - v_i+1): the kick of the step used the forces before its moves (the
// projection after the drift books + dt/2: its moves change the next step's forces).
TEST(ProjectionCheck, TakesOutWhatTheAllowanceLeftAndBooksAMoveBeforeTheDrift) {
  const Real overlap = 8e-6, slop = 0.5e-6, maxMove = 10e-6, dt = 2e-9;
  for (bool check : {false, true}) {
    Fabric f = crossing(overlap);
    for (Index i = 0; i < f.nNodes(); ++i) f.vel[i] = Vec3(30 * std::sin(1.0 + i), -20 * std::cos(2.0 * i), 10 * i - 25);
    std::vector<CPContact> contacts{measured(f)};
    ASSERT_NEAR(contacts[0].gap, -overlap, 1e-12);
    std::vector<BodyContact> none;
    std::vector<RigidBody> bodies;
    const Vec3Array before = f.pos;
    PositionProjection proj;
    ProjectionReport rep;
    // An allowance of 20 um: all of the overlap is the flattening's to take, in both calls.
    proj.project(f, contacts, none, bodies, [](const CPContact&) { return Real(20e-6); }, 8, slop, maxMove,
                 SectionRule::ConstantArea, dt, rep, SweepOrder::Coloured, check ? 2e-6 : -1);
    const CPContact after = measured(f);
    if (!check) {
      EXPECT_EQ(rep.pushed, 0);
      EXPECT_EQ(f.pos, before);
      EXPECT_EQ(rep.energy, 0);
      continue;
    }
    EXPECT_GT(rep.pushed, 0);
    // Taken out to within the slop, less its rebound (one linearised push: to 1 % of the slop).
    EXPECT_NEAR(after.gap, -(1 - kRebound) * slop, 0.01 * slop) << "taken out to within the slop, less its rebound";
    Real expected = 0;
    for (Index e = 0; e < f.nElems(); ++e) {
      const Index i = f.elem0[e];
      expected += energyOf(f, f.pos, e) - energyOf(f, before, e) -
                  0.5 * dt * (forceOf(f, f.pos, e) - forceOf(f, before, e)).dot(f.vel[i] - f.vel[i + 1]);
    }
    EXPECT_NE(expected, 0);
    EXPECT_NEAR(rep.energy, expected, 1e-9 * std::abs(expected));
  }
}

// Only contacts deeper than checkDepth seed the check: a shallower overlap is left to the rows, as
// is the same overlap with the check off.
TEST(ProjectionCheck, LeavesOverlapsBelowItsDepth) {
  for (Real overlap : {1.5e-6, 2.5e-6}) {
    Fabric f = crossing(overlap);
    std::vector<CPContact> contacts{measured(f)};
    std::vector<BodyContact> none;
    std::vector<RigidBody> bodies;
    PositionProjection proj;
    ProjectionReport rep;
    proj.project(f, contacts, none, bodies, [](const CPContact&) { return Real(0); }, 8, 0.5e-6, 10e-6,
                 SectionRule::ConstantArea, 1e-9, rep, SweepOrder::Coloured, 2e-6);
    EXPECT_EQ(rep.pushed > 0, overlap > 2e-6) << overlap;
    if (overlap > 2e-6) EXPECT_NEAR(measured(f).gap, -(1 - kRebound) * 0.5e-6, 0.5e-8) << overlap;
    else EXPECT_NEAR(measured(f).gap, -overlap, 1e-12) << overlap;
  }
}

// A check moves a node at most kCheckTravel x maxMove; the projection after the same step's drift
// moves it only as far as the check left of its own kProjectionTravel x maxMove; the next step's
// projection has its whole budget again. A 60 um overlap with maxMove 4 um uses them up (its
// nodes of weight 0.75 would move 36 um).
TEST(ProjectionCheck, CountsAgainstTheTravelOfTheProjectionAfterTheDrift) {
  const Real overlap = 60e-6, maxMove = 4e-6;
  Fabric f = crossing(overlap);
  std::vector<CPContact> contacts{measured(f)};
  std::vector<BodyContact> none;
  std::vector<RigidBody> bodies;
  const auto zero = [](const CPContact&) { return Real(0); };
  const auto most = [&](const Vec3Array& from) {
    Real m = 0;
    for (Index i = 0; i < f.nNodes(); ++i) m = std::max(m, (f.pos[i] - from[i]).norm());
    return m;
  };
  const Vec3Array start = f.pos;
  PositionProjection proj;
  ProjectionReport rep;
  proj.project(f, contacts, none, bodies, zero, 50, 0.5e-6, maxMove, SectionRule::ConstantArea, 1e-9, rep,
               SweepOrder::Coloured, 2e-6);
  EXPECT_LE(most(start), kCheckTravel * maxMove * (1 + 1e-12));
  EXPECT_GT(most(start), (kCheckTravel - 0.5) * maxMove) << "the check's budget is used";
  const Vec3Array checked = f.pos;
  proj.project(f, contacts, none, bodies, zero, 50, 0.5e-6, maxMove, SectionRule::ConstantArea, 1e-9, rep);
  for (Index i = 0; i < f.nNodes(); ++i) {  // a node's travel is at least its displacement
    const Real left = std::max(Real(0), kProjectionTravel * maxMove - (checked[i] - start[i]).norm());
    EXPECT_LE((f.pos[i] - checked[i]).norm(), left + 1e-15) << i;
  }
  // The next projection (a new step) has its own budget again.
  const Vec3Array mid = f.pos;
  proj.project(f, contacts, none, bodies, zero, 50, 0.5e-6, maxMove, SectionRule::ConstantArea, 1e-9, rep);
  EXPECT_GT(most(mid), maxMove) << "the nodes the check moved 24 um move again";
  EXPECT_NEAR(measured(f).gap, -(1 - kRebound) * 0.5e-6, 0.5e-8);
}

// In a step: sections that cannot flatten (flattening none) leave an 8 um overlap of two crossing
// yarns; with the check it is out before the rows (the step's measured overlap is the slop, the
// check met 8 um); without it the rows hold it and the step reports it. The books account for the
// check's moves: the balance is the same as without them (the leapfrog's own error of a step of
// these loaded springs) to a thousandth of the energy the moves put in.
TEST(ProjectionCheck, InAStepTheOverlapIsOutBeforeTheRowsAndTheBooksClose) {
  Real balance[2], put = 0;
  for (Real depth : {Real(-1), Real(2e-6)}) {
    FabricEngine e(crossing(8e-6));
    ContactParams p;
    p.flattening = Flattening::None;
    p.projectionCheck = depth;
    // The chords' contact: its closest points follow the projection's moves, so with or without the
    // check the step ends in the same place (a persistent crossing holds its points for the step,
    // and the two runs' ends differ by the step's slide along the yarn).
    p.crossings = Crossings::Chords;
    e.enableCollisions(p);
    e.step(0.5 * e.criticalDt());
    const CollisionStats& st = e.collisions()->stats;
    const EnergyBooks b = e.dynamics().energy();
    if (depth < 0) {
      EXPECT_NEAR(st.penetration, 8e-6, 1e-12);
      EXPECT_EQ(st.checks, 0);
    } else {
      EXPECT_LE(st.penetration, p.projectionSlop + 1e-12);
      EXPECT_EQ(st.checks, 1);
      EXPECT_NEAR(st.maxChecked, 8e-6, 1e-12);
      put = -b.projection;  // the book holds what the projection took out
    }
    balance[depth >= 0] = b.balanceError();
  }
  EXPECT_GT(put, 0) << "the moves stretch the loaded springs";
  EXPECT_NEAR(balance[1], balance[0], 1e-3 * put);
}
