// Narrow phase (pkg/geom/SeparatingAxis) against an independent brute force (vertex projections on
// the 15 axes) on 1e5 random box pairs, a third of them yarn-shaped: overlap yes/no, the exact
// minimum depth, and contact points on both surfaces.
#include "box_util.hpp"
#include "chain_util.hpp"
#include "geom/SeparatingAxis.hpp"
#include <gtest/gtest.h>

using namespace woven;
using namespace woven_test;

namespace {
const int kPairs = static_cast<int>(woven_test::runLength(100000, 10));
}

TEST(SeparatingAxis, OverlapAndDepthMatchBruteForce) {
  std::mt19937 rng(2024);
  int overlapping = 0, edgeAxes = 0;
  for (int k = 0; k < kPairs; ++k) {
    const OBB a = randomBox(rng, 1.0), b = randomBox(rng, 1.0);
    const Real ref = bruteForceDepth(a, b);
    const BoxContact c = obbContact(a, b);
    if (std::abs(ref) <= 1e-9) continue;  // within 1e-9 m of touching: either answer is right
    ASSERT_EQ(c.overlap, ref > 0) << "pair " << k << " brute-force depth " << ref;
    ASSERT_EQ(obbOverlap(a, b), ref > 0) << "pair " << k;
    if (!c.overlap) continue;
    ++overlapping;
    edgeAxes += c.axis >= 6;
    // the TD depth is the exact minimum over the 15 axes
    ASSERT_NEAR(c.depth, ref, 1e-9) << "pair " << k << " axis " << c.axis;
    // the normal points from A to B and moving B by depth*normal makes them touch
    OBB moved = b;
    moved.centre += c.depth * c.normal;
    ASSERT_NEAR(projectedOverlap(a, moved, c.normal), 0.0, 1e-9);
    ASSERT_GT(c.nPoints, 0) << "pair " << k;
    for (int i = 0; i < c.nPoints; ++i) {
      const BoxContactPoint& p = c.points[i];
      EXPECT_NEAR(a.outside(p.onA), 0.0, 1e-9) << "pair " << k << " point " << i << " not on A's surface";
      EXPECT_NEAR(b.outside(p.onB), 0.0, 1e-9) << "pair " << k << " point " << i << " not on B's surface";
      EXPECT_GE(p.depth, -1e-9);
      EXPECT_LE(p.depth, c.depth + 1e-9);
      EXPECT_NEAR((p.onA - p.onB).dot(c.normal), p.depth, 1e-9);
    }
  }
  // the sample exercises both answers and both kinds of axis
  EXPECT_GT(overlapping, kPairs / 10);
  EXPECT_GT(edgeAxes, 100);
}

TEST(SeparatingAxis, ParallelEdgesAreNotFalselySeparated) {
  // Two identical yarn-shaped boxes, the second rotated by a tiny angle about the common long axis
  // and overlapping by 1e-3 of the thickness: A_0 x B_0 ~ 0 must not become a separating axis.
  OBB a;
  a.extent = Vec3(1.0, 0.05, 0.02);
  for (Real angle : {0.0, 1e-14, 1e-10, 1e-7}) {
    OBB b = a;
    b.axes = Eigen::AngleAxis<Real>(angle, Vec3::UnitX()).toRotationMatrix();
    b.centre = Vec3(0.3, 0.0, 0.04 - 2e-5);
    const BoxContact c = obbContact(a, b);
    ASSERT_TRUE(c.overlap) << "angle " << angle;
    EXPECT_NEAR(c.depth, bruteForceDepth(a, b), 1e-9) << "angle " << angle;
    EXPECT_NEAR(std::abs(c.normal.z()), 1.0, 1e-6);
  }
}

TEST(SeparatingAxis, FaceFaceContactIsTheClippedOverlapPatch) {
  // A unit cube resting 0.1 m deep on a wider slab: four points, the cube's bottom corners.
  OBB slab, cube;
  slab.extent = Vec3(2, 2, 0.5);
  cube.extent = Vec3(0.5, 0.5, 0.5);
  cube.centre = Vec3(0.2, -0.3, 0.9);
  const BoxContact c = obbContact(slab, cube);
  ASSERT_TRUE(c.overlap);
  EXPECT_EQ(c.axis, 2);
  EXPECT_NEAR(c.depth, 0.1, 1e-12);
  EXPECT_NEAR(c.normal.z(), 1.0, 1e-12);
  ASSERT_EQ(c.nPoints, 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(c.points[i].onB.z(), 0.4, 1e-12);
    EXPECT_NEAR(std::abs(c.points[i].onB.x() - 0.2), 0.5, 1e-12);
    EXPECT_NEAR(c.points[i].onA.z(), 0.5, 1e-12);
  }
}

TEST(SeparatingAxis, MovingBoxesFindTheFirstTimeOfContact) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<Real> u(-1, 1);
  int hits = 0;
  const int pairs = static_cast<int>(runLength(4000, 10)), grid = static_cast<int>(runLength(200, 4));
  for (int k = 0; k < pairs; ++k) {
    const OBB a = randomBox(rng, 2.0), b = randomBox(rng, 2.0);
    const Vec3 va(u(rng), u(rng), u(rng)), vb = 3 * Vec3(u(rng), u(rng), u(rng));
    const Real dt = 1.0;
    const SweptContact s = obbFirstContact(a, va, b, vb, dt);
    auto at = [&](Real t, OBB& A, OBB& B) {
      A = a, B = b;
      A.centre += va * t;
      B.centre += vb * t;
    };
    OBB A, B;
    if (s.hit) {
      ++hits;
      ASSERT_GE(s.time, 0.0);
      ASSERT_LE(s.time, dt);
      at(s.time, A, B);
      const Real d = bruteForceDepth(A, B, 0.0);
      if (s.time > 0) EXPECT_NEAR(d, 0.0, 1e-9) << "pair " << k << ": not touching at the first contact";
      else EXPECT_GE(d, -1e-9);
      EXPECT_TRUE(s.contact.overlap) << "pair " << k;
      if (s.time > 1e-6) {  // just before: apart
        at(s.time - 1e-6, A, B);
        EXPECT_LT(bruteForceDepth(A, B, 0.0), 1e-9) << "pair " << k;
      }
    } else {  // never overlapping in [0, dt]: check on a fine grid of times
      for (int i = 0; i <= grid; ++i) {
        at(dt * i / grid, A, B);
        ASSERT_LE(bruteForceDepth(A, B, 0.0), 1e-9) << "pair " << k << " overlaps at t = " << dt * i / grid;
      }
    }
  }
  EXPECT_GT(hits, pairs / 20);
}

TEST(SeparatingAxis, NoTunnellingAt1000MetresPerSecond) {
  // A CP-sized box (0.2 mm long, 0.65 x 0.11 mm section) crossing another at 1000 m/s relative
  // speed: apart at the start and at the end of a step of 1.1e-7 s (twice its thickness travelled
  // per step), yet the moving test finds the contact inside the step.
  OBB a, b;
  a.extent = Vec3(0.1e-3, 0.325e-3, 0.055e-3);
  b.extent = Vec3(0.325e-3, 0.1e-3, 0.055e-3);
  b.centre = Vec3(0, 0, 0.12e-3);
  const Vec3 vb(0, 0, -1000.0);
  const Real dt = 2.4e-7;
  OBB end = b;
  end.centre += vb * dt;
  ASSERT_FALSE(obbOverlap(a, b));
  ASSERT_FALSE(obbOverlap(a, end));
  const SweptContact s = obbFirstContact(a, Vec3::Zero(), b, vb, dt);
  ASSERT_TRUE(s.hit);
  EXPECT_NEAR(s.time, (0.12e-3 - 0.11e-3) / 1000.0, 1e-15);
  EXPECT_NEAR(std::abs(s.contact.normal.z()), 1.0, 1e-9);
}
