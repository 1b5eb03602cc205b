// The gap functions of the contact model `gap` (geom/GapFunction.hpp) against their impulse rows:
// for every contact kind, central finite differences of g in each node coordinate (and in a body's
// translation and rotation) on 1e4 random configurations must equal the row the impulse law builds
// (weights w_k times the normal; a body's n and arm x n). An independent oracle of the row: g is
// evaluated as a plain function of the positions, the row from the contact's normal and weights.
// Also: closest points on an ellipse against a dense sampling, and the side of the normal.
#include "chain_util.hpp"
#include "geom/GapFunction.hpp"
#include "shape/Cylinder.hpp"
#include <gtest/gtest.h>
#include <cmath>
#include <random>

using namespace woven;
using namespace woven_test;

namespace {

constexpr int kConfigs = 10000;

Vec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<Real> n(0, 1);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

// Two single-CP yarns through the given end points; each node's section flattened at random
// (eps in [0, 0.6)) along a random direction across its CP.
Fabric randomPair(std::mt19937_64& rng, const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  YarnSection sec;
  sec.width = 0.65e-3, sec.thickness = 0.11e-3;
  Fabric f;
  f.addYarn({a0, a1}, km2Material(), sec);
  f.addYarn({b0, b1}, km2Material(), sec);
  std::uniform_real_distribution<Real> eps(0, 0.6);
  for (Index k = 0; k < 4; ++k) {
    const Vec3 t = (k < 2 ? a1 - a0 : b1 - b0).normalized();
    Vec3 d = randomUnit(rng);
    f.secDir[k] = (d - d.dot(t) * t).normalized();
    f.secFlat[k] = eps(rng);
  }
  return f;
}

// Row of a CP-CP contact as ImpulseLaw builds it: node weights -(1-sA), -sA, 1-sB, sB along n.
void pairRow(const CPContact& c, Vec3 grad[4]) {
  const Real w[4] = {-(1 - c.sA), -c.sA, 1 - c.sB, c.sB};
  for (int k = 0; k < 4; ++k) grad[k] = w[k] * c.normal;
}

// Central differences of g (remeasure with the sections held, the contact's normal as the side)
// against the row; false when a clamp of the closest points switches within the step (a kink of g).
bool pairMatches(Fabric f, const CPContact& c0, Real h, Real tol, Real& worst) {
  Vec3 row[4];
  pairRow(c0, row);
  for (int k = 0; k < 4; ++k)
    for (int d = 0; d < 3; ++d) {
      CPContact p = c0, m = c0;
      const Real x = f.pos[k][d];
      f.pos[k][d] = x + h;
      remeasure(f, p, SectionRule::ConstantArea, false);
      f.pos[k][d] = x - h;
      remeasure(f, m, SectionRule::ConstantArea, false);
      f.pos[k][d] = x;
      const auto clamp = [](Real s) { return s <= 0 ? 0 : (s >= 1 ? 2 : 1); };
      if (clamp(p.sA) != clamp(m.sA) || clamp(p.sB) != clamp(m.sB) || clamp(p.sA) != clamp(c0.sA) ||
          clamp(p.sB) != clamp(c0.sB))
        return false;
      const Real fd = (p.gap - m.gap) / (2 * h);
      worst = std::max(worst, std::abs(fd - row[k][d]));
      EXPECT_NEAR(fd, row[k][d], tol) << "node " << k << " axis " << d;
    }
  return true;
}

}  // namespace

// Crossing pieces (more than 30 degrees apart, up to 0.4 mm between the axes, ends anywhere): the
// distance of the closest points minus the held half-thicknesses; its gradient is the row exactly.
TEST(GapFunction, CrossingRowIsTheGradientOfTheGap) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0;
  Real worst = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 tA = randomUnit(rng);
    Vec3 tB = randomUnit(rng);
    if (std::abs(tA.dot(tB)) > std::cos(30 * M_PI / 180)) tB = tA.cross(tB).normalized();
    const Vec3 cA = 0.3e-3 * Vec3(u(rng), u(rng), u(rng)), cB = 0.3e-3 * Vec3(u(rng), u(rng), u(rng));
    const Real lA = 0.4e-3 + 0.6e-3 * (u(rng) + 1) / 2, lB = 0.4e-3 + 0.6e-3 * (u(rng) + 1) / 2;
    Fabric f = randomPair(rng, cA - 0.5 * lA * tA, cA + 0.5 * lA * tA, cB - 0.5 * lB * tB, cB + 0.5 * lB * tB);
    ASSERT_FALSE(sideBySide(f, 0, 1, false));
    CPContact c[2];
    ASSERT_EQ(pairGaps(f, 0, 1, false, SectionRule::ConstantArea, nullptr, c), 1);
    EXPECT_EQ(c[0].kind, ContactKind::Cross);
    if (std::abs(c[0].gap + c[0].hA + c[0].hB) < 1e-9) continue;  // the axes meet: no direction
    tested += pairMatches(f, c[0], 1e-11, 1e-5, worst);
  }
  EXPECT_GT(tested, 0.95 * kConfigs) << "configurations on a kink of g";
  RecordProperty("worst", std::to_string(worst));
}

// Side-by-side pieces (0 to 19 degrees apart: classed Side on entry), one or two points at the ends
// of the part alongside: A's point fixed along A, B's the closest to it; the same gradient.
TEST(GapFunction, SideBySideRowIsTheGradientOfTheGap) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<Real> u(-1, 1), angle(0, 19 * M_PI / 180);
  int tested = 0, two = 0;
  Real worst = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 tA = randomUnit(rng);
    const Vec3 axis = tA.cross(randomUnit(rng)).normalized();
    const Vec3 tB = Eigen::AngleAxis<Real>(angle(rng), axis) * tA;
    const Vec3 cA = Vec3::Zero();
    Vec3 off = randomUnit(rng);
    off -= off.dot(tA) * tA;
    const Vec3 cB = 0.6e-3 * u(rng) * tA + 0.5e-3 * (u(rng) + 1.2) / 2.2 * off.normalized();
    Fabric f = randomPair(rng, cA - 0.4e-3 * tA, cA + 0.4e-3 * tA, cB - 0.4e-3 * tB, cB + 0.4e-3 * tB);
    ASSERT_TRUE(sideBySide(f, 0, 1, false));
    CPContact c[2];
    const int m = pairGaps(f, 0, 1, true, SectionRule::ConstantArea, nullptr, c);
    two += m == 2;
    for (int q = 0; q < m; ++q) {
      EXPECT_EQ(c[q].kind, ContactKind::Side);
      tested += pairMatches(f, c[q], 1e-11, 1e-5, worst);
    }
  }
  EXPECT_GT(two, kConfigs / 4);  // pieces alongside each other get the two-point form
  EXPECT_GT(tested, kConfigs);
}

namespace {
// A body with one part (a sphere of radius R, or a box of half-sizes H) offset from its centre of
// mass, turned at random: a clump member, so that the arm of the row is tested too.
RigidBody randomBody(std::mt19937_64& rng, bool sphere, const Vec3& partCentre) {
  std::uniform_real_distribution<Real> u(0.5, 1.5);
  RigidBody b;
  RigidPart part;
  part.type = sphere ? RigidPart::Type::Sphere : RigidPart::Type::Box;
  part.radius = 1.5e-3 * u(rng);
  part.halfSize = 1e-3 * Vec3(u(rng), u(rng), u(rng));
  part.offset = 0.5e-3 * randomUnit(rng);
  part.ori = Quat(Eigen::AngleAxis<Real>(u(rng), randomUnit(rng)));
  b.parts.push_back(part);
  b.mass = 1e-3, b.inertia = Vec3::Constant(1e-9);
  b.ori = Quat(Eigen::AngleAxis<Real>(3 * u(rng), randomUnit(rng)));
  b.pos = partCentre - b.ori * part.offset;
  return b;
}

// Central differences of a body contact's g in the CP's node coordinates and the body's
// translation and rotation (about its centre of mass) against the row: -w_k n on the CP's nodes,
// n and arm x n on the body, arm = point - centre of mass.
void bodyMatches(Fabric& f, RigidBody& b, const BodyContact& c0, Real h, Real tol, Real& worst) {
  const Real w[2] = {-(1 - c0.s), -c0.s};
  const Vec3 arm = c0.point - b.pos, rn = arm.cross(c0.normal);
  const auto g = [&](const RigidBody& body) {
    BodyContact c = c0;
    remeasureBody(f, body, c);
    return c.gap;
  };
  for (int k = 0; k < 2; ++k)
    for (int d = 0; d < 3; ++d) {
      const Real x = f.pos[k][d];
      f.pos[k][d] = x + h;
      const Real gp = g(b);
      f.pos[k][d] = x - h;
      const Real gm = g(b);
      f.pos[k][d] = x;
      const Real fd = (gp - gm) / (2 * h), row = w[k] * c0.normal[d];
      worst = std::max(worst, std::abs(fd - row));
      EXPECT_NEAR(fd, row, tol) << "node " << k << " axis " << d;
    }
  for (int d = 0; d < 3; ++d) {
    RigidBody p = b, m = b;
    p.pos[d] += h, m.pos[d] -= h;
    const Real fd = (g(p) - g(m)) / (2 * h);
    worst = std::max(worst, std::abs(fd - c0.normal[d]));
    EXPECT_NEAR(fd, c0.normal[d], tol) << "body translation " << d;
    const Real th = h / 1e-3;  // a turn moving the part by about h
    p = b, m = b;
    p.ori = Quat(Eigen::AngleAxis<Real>(th, Vec3::Unit(d))) * b.ori;
    m.ori = Quat(Eigen::AngleAxis<Real>(-th, Vec3::Unit(d))) * b.ori;
    const Real fr = (g(p) - g(m)) / (2 * th);
    worst = std::max(worst, std::abs(fr - rn[d]) / 1e-3);
    EXPECT_NEAR(fr, rn[d], tol * 1e-3) << "body rotation " << d;
  }
}
}  // namespace

// A CP and a sphere part: the distance from the centre to the closest point of the held section
// ellipse, minus R; its gradient in the nodes, the translation and the rotation is the row.
TEST(GapFunction, SphereRowIsTheGradientOfTheGap) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0, ends = 0;
  Real worst = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 t = randomUnit(rng);
    Fabric f = randomPair(rng, -0.4e-3 * t, 0.4e-3 * t, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    // The sphere's centre beside the CP (or beyond an end), its surface within 0.2 mm of the yarn.
    Vec3 side = randomUnit(rng);
    side -= side.dot(t) * t;
    RigidBody b = randomBody(rng, true, Vec3::Zero());
    const Real R = b.parts[0].radius;
    const Vec3 centre = 0.6e-3 * u(rng) * t + (R + 0.2e-3 * u(rng) + 0.3e-3) * side.normalized();
    b.pos += centre - b.partCentre(0);
    BodyContact c[2];
    const int m = bodyGap(f, 0, b, 0, 1e-3, 1, SectionRule::ConstantArea, c);
    ASSERT_GE(m, 1);
    if (c[0].s <= 1e-6 || c[0].s >= 1 - 1e-6) continue;  // beyond an end: a kink of s, tested below
    for (int q = 0; q < m; ++q) bodyMatches(f, b, c[q], 1e-11, 1e-5, worst);  // q = 1: held at an end node
    ends += m - 1;
    ++tested;
  }
  EXPECT_GT(tested, kConfigs / 2);
  EXPECT_GT(ends, 0) << "some configurations hold an end node too";
}

// A CP and a box part: one contact per end section against the box face that leaves the most room;
// its gradient in the nodes, the translation and the rotation is the row.
TEST(GapFunction, BoxRowIsTheGradientOfTheGap) {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0;
  Real worst = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 t = randomUnit(rng);
    const Vec3 c0 = 1.5e-3 * Vec3(u(rng), u(rng), u(rng));
    Fabric f = randomPair(rng, c0 - 0.4e-3 * t, c0 + 0.4e-3 * t, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    RigidBody b = randomBody(rng, false, Vec3::Zero());
    BodyContact c[2];
    const int m = bodyGap(f, 0, b, 0, 1.0, 1.0, SectionRule::ConstantArea, c);  // a huge reach: listed
    ASSERT_EQ(m, 2);
    for (int q = 0; q < m; ++q) {
      // Away from a tie between two faces (where the face chosen would switch within the step).
      BodyContact p = c[q];
      bodyMatches(f, b, p, 1e-11, 1e-5, worst);
      ++tested;
    }
  }
  EXPECT_EQ(tested, 2 * kConfigs);
}

namespace {
// A cylinder part (half of them with the FSP's chisel nose, at random angle and land) offset from
// the body's centre of mass and turned at random.
RigidBody randomCylinder(std::mt19937_64& rng, const Vec3& partCentre) {
  std::uniform_real_distribution<Real> u(0.5, 1.5), unit(0, 1);
  RigidBody b;
  RigidPart part;
  part.type = RigidPart::Type::Cylinder;
  part.radius = 1.5e-3 * u(rng);
  part.halfLength = 1.5e-3 * u(rng);
  if (unit(rng) < 0.5) {
    part.landHalfWidth = part.radius * 0.9 * unit(rng);
    // flats that end before the tail: (R - w) / tan(alpha) < 2H
    const Real minAngle = std::atan((part.radius - part.landHalfWidth) / (2 * part.halfLength));
    part.chiselAngle = minAngle + (0.5 * M_PI - minAngle) * (0.05 + 0.9 * unit(rng));
  }
  part.offset = 0.5e-3 * randomUnit(rng);
  part.ori = Quat(Eigen::AngleAxis<Real>(u(rng), randomUnit(rng)));
  b.parts.push_back(part);
  b.mass = 1e-3, b.inertia = Vec3::Constant(1e-9);
  b.ori = Quat(Eigen::AngleAxis<Real>(3 * u(rng), randomUnit(rng)));
  b.pos = partCentre - b.ori * part.offset;
  b.validate();
  return b;
}

// Is y (part frame) inside the cylinder part, within tol [m]?
bool insideCylinder(const RigidPart& p, const Vec3& y, Real tol) {
  if (std::hypot(y.x(), y.y()) > p.radius + tol || std::abs(y.z()) > p.halfLength + tol) return false;
  if (!(p.chiselAngle > 0)) return true;
  const Real ca = std::cos(p.chiselAngle), sa = std::sin(p.chiselAngle);
  const Real limit = p.landHalfWidth * ca + p.halfLength * sa;
  return std::abs(y.x()) * ca + y.z() * sa <= limit + tol;
}
}  // namespace

// The cylinder's (and the chiselled cylinder's) lowest point along n against an independent
// oracle: the minimum over a dense sampling of the solid's surface (every point that lies inside
// the solid, on its round surface, its end faces and its flats). The exact minimum lies at or
// below every sample, and within the sampling step of the best one.
TEST(GapFunction, CylinderSupportMatchesADenseSampling) {
  std::mt19937_64 rng(16);
  for (int n = 0; n < 300; ++n) {
    const RigidPart p = randomCylinder(rng, Vec3::Zero()).parts[0];
    const Vec3 dir = randomUnit(rng);
    const Real exact = cylinderMinAlong(p, dir);
    const Real R = p.radius, H = p.halfLength;
    Real best = INFINITY;
    const int NT = 720, NZ = 400, NR = 100;
    const auto sample = [&](const Vec3& y) {
      if (insideCylinder(p, y, 1e-12)) best = std::min(best, y.dot(dir));
    };
    for (int i = 0; i < NT; ++i) {
      const Real th = 2 * M_PI * i / NT, c = std::cos(th), sn = std::sin(th);
      for (int k = 0; k <= NZ; ++k) sample(Vec3(R * c, R * sn, -H + 2 * H * k / NZ));  // round surface
      for (int k = 0; k <= NR; ++k) {
        const Real r = R * k / NR;
        sample(Vec3(r * c, r * sn, -H)), sample(Vec3(r * c, r * sn, H));  // end faces
      }
      if (p.chiselAngle > 0)  // the flats: for each height, the point where the flat meets the azimuth's ray
        for (int k = 0; k <= NZ; ++k) {
          const Real z = -H + 2 * H * k / NZ, x = p.landHalfWidth + (H - z) * std::tan(p.chiselAngle);
          const Real y = 1.2 * R * (2.0 * i / NT - 1);
          sample(Vec3(x, y, z)), sample(Vec3(-x, y, z));
        }
    }
    ASSERT_TRUE(std::isfinite(best));
    EXPECT_LE(exact, best + 1e-15) << "n " << n;
    EXPECT_GE(exact, best - 0.05 * (R + H)) << "n " << n;  // grossly wrong only
    EXPECT_NEAR(exact, best, 2e-3 * (R + H)) << "n " << n;  // the sampling's resolution
  }
}

// A CP and a cylinder part (RCC or FSP): the box's separating-plane form on the direction that leaves
// the CP the most room; its gradient in the nodes, the translation and the rotation is the row.
TEST(GapFunction, CylinderRowIsTheGradientOfTheGap) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0;
  Real worst = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 t = randomUnit(rng);
    const Vec3 c0 = 2.5e-3 * Vec3(u(rng), u(rng), u(rng));
    Fabric f = randomPair(rng, c0 - 0.4e-3 * t, c0 + 0.4e-3 * t, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    RigidBody b = randomCylinder(rng, Vec3::Zero());
    BodyContact c[2];
    const int m = bodyGap(f, 0, b, 0, 1.0, 1.0, SectionRule::ConstantArea, c);  // a huge reach: listed
    ASSERT_EQ(m, 2);
    for (int q = 0; q < m; ++q) {
      bodyMatches(f, b, c[q], 1e-11, 1e-5, worst);
      ++tested;
    }
  }
  EXPECT_EQ(tested, 2 * kConfigs);
}

// For a round cylinder and a circular section (a disk of radius r0 across the yarn) the gap lies
// between two independent oracles: at least the distance from the node to the cylinder minus r0 (the
// disk lies within the ball of radius r0: the candidate directions hold the closest point's), at
// most the distance between the disk and the cylinder (a separating plane never reports more room
// than there is), the latter from a dense sampling of the disk and the closed-form distance of a
// point to a cylinder (its axial and radial coordinates clamped). Separated configurations.
TEST(GapFunction, CylinderGapLiesBetweenTheBallAndTheDiskDistances) {
  std::mt19937_64 rng(18);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0;
  Real worstBelow = 0;
  // (sanitizer builds: a tenth of the configurations; its dense sampling was 34 s of their tests)
  const long configs = runLength(kConfigs, 10);
  for (long n = 0; n < configs; ++n) {
    RigidBody b = randomCylinder(rng, Vec3::Zero());
    RigidPart& p = b.parts[0];
    p.chiselAngle = 0, p.landHalfWidth = 0;
    const Vec3 t = randomUnit(rng);
    const Vec3 c0 = 3e-3 * Vec3(u(rng), u(rng), u(rng));
    Fabric f = randomPair(rng, c0 - 0.4e-3 * t, c0 + 0.4e-3 * t, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    for (Index k = 0; k < 2; ++k) f.secFlat[k] = 0;  // circular
    BodyContact c[2];
    ASSERT_EQ(bodyGap(f, 0, b, 0, 1.0, 1.0, SectionRule::ConstantArea, c), 2);
    const Mat3 A = b.partAxes(0);
    const auto dist = [&](const Vec3& x) {  // distance of a point outside the round cylinder, or - depth inside
      const Vec3 q = A.transpose() * (x - b.partCentre(0));
      const Real dr = std::hypot(q.x(), q.y()) - p.radius, dz = std::abs(q.z()) - p.halfLength;
      return (dr > 0 || dz > 0) ? std::hypot(std::max(dr, Real(0)), std::max(dz, Real(0))) : std::max(dr, dz);
    };
    const Vec3 e1 = t.unitOrthogonal(), e2 = t.cross(e1);
    for (int k = 0; k < 2; ++k) {
      const Real r0 = f.secRadius[k], ball = dist(f.pos[k]) - r0;
      if (ball < 1e-5) continue;  // separated configurations only
      Real disk = INFINITY;
      for (int i = 0; i < 256; ++i)
        for (int j = 1; j <= 16; ++j) {
          const Real th = 2 * M_PI * i / 256, r = r0 * j / 16;
          disk = std::min(disk, dist(f.pos[k] + r * (std::cos(th) * e1 + std::sin(th) * e2)));
        }
      disk = std::min(disk, dist(f.pos[k]));
      EXPECT_GE(c[k].gap, ball - 1e-12) << "n " << n << " node " << k;
      EXPECT_LE(c[k].gap, disk + 1e-12) << "n " << n << " node " << k;
      worstBelow = std::max(worstBelow, disk - c[k].gap);
      ++tested;
    }
  }
  EXPECT_GT(tested, configs / 2);
  RecordProperty("largest_gap_below_disk_distance_m", std::to_string(worstBelow));
}

// The closest point of an ellipse against a dense sampling of its boundary (2e5 points), inside and
// outside, for flat and round ellipses.
TEST(GapFunction, ClosestPointOnAnEllipseMatchesADenseSampling) {
  std::mt19937_64 rng(15);
  std::uniform_real_distribution<Real> u(-1, 1), ratio(0.05, 1);
  for (int n = 0; n < 200; ++n) {
    const Real a = 1e-4, b = a * ratio(rng);
    const bool swap = n % 2;
    const Real A = swap ? b : a, B = swap ? a : b;
    const Real px = 2e-4 * u(rng), py = 2e-4 * u(rng);
    Real qx, qy;
    const bool outside = closestOnEllipse(A, B, px, py, qx, qy);
    EXPECT_EQ(outside, (px / A) * (px / A) + (py / B) * (py / B) >= 1);
    EXPECT_NEAR((qx / A) * (qx / A) + (qy / B) * (qy / B), 1.0, 1e-9);
    Real best = INFINITY;
    for (int k = 0; k < 200000; ++k) {
      const Real th = 2 * M_PI * k / 200000;
      best = std::min(best, std::hypot(A * std::cos(th) - px, B * std::sin(th) - py));
    }
    EXPECT_NEAR(std::hypot(qx - px, qy - py), best, 1e-12 + 2e-9);  // sampling step ~3e-9 m
    EXPECT_LE(std::hypot(qx - px, qy - py), best + 1e-15);
  }
}

// A piece pushed through another keeps its side: g goes negative past the axis instead of growing
// again (where the closest points lie inside both pieces); round the end of the other piece the
// side may change.
TEST(GapFunction, APiecePushedThroughKeepsItsSide) {
  std::mt19937_64 rng(16);
  Fabric f = randomPair(rng, Vec3(-0.4e-3, 0, 0), Vec3(0.4e-3, 0, 0), Vec3(0, -0.4e-3, 0.2e-3), Vec3(0, 0.4e-3, 0.2e-3));
  CPContact c[2];
  ASSERT_EQ(pairGaps(f, 0, 1, false, SectionRule::ConstantArea, nullptr, c), 1);
  EXPECT_NEAR(c[0].normal.z(), 1.0, 1e-12);
  const Real g0 = c[0].gap;
  for (Index k : {2, 3}) f.pos[k].z() = -0.05e-3;  // B now 0.05 mm below A's axis
  remeasure(f, c[0], SectionRule::ConstantArea, false);
  EXPECT_NEAR(c[0].normal.z(), 1.0, 1e-12);
  EXPECT_NEAR(c[0].gap, g0 - 0.25e-3, 1e-12);
  // Round A's end: B beyond x = 0.4 mm, then below: the closest point of A is its end node.
  for (Index k : {2, 3}) f.pos[k].x() = 0.9e-3;
  remeasure(f, c[0], SectionRule::ConstantArea, false);
  EXPECT_LT(c[0].normal.z(), 0);
  EXPECT_GT(c[0].gap, 0);
}

// The measure memory (capMeasure): the sections' measure hA + hB may grow between steps only into
// the room the axes leave. Exact arithmetic on a crossing: r = gap + hA + hB is kept, the measure is
// min(H, max(remembered, r)) shared in the proportion hA : hB, and the point stays half way.
TEST(GapFunction, MeasureMemoryLetsTheMeasureGrowOnlyIntoRoom) {
  std::mt19937_64 rng(21);
  for (int trial = 0; trial < 1000; ++trial) {
    const Real z = 0.05e-3 + 0.1e-3 * std::uniform_real_distribution<Real>(0, 1)(rng);
    Fabric f = randomPair(rng, Vec3(-0.4e-3, 0, 0), Vec3(0.4e-3, 0, 0), Vec3(0, -0.4e-3, z), Vec3(0, 0.4e-3, z));
    CPContact c[2];
    ASSERT_EQ(pairGaps(f, 0, 1, false, SectionRule::ConstantArea, nullptr, c), 1);
    const CPContact c0 = c[0];
    const Real H = c0.hA + c0.hB, r = c0.gap + H;
    ASSERT_NEAR(r, z, 1e-15);
    for (const Real remembered : {0.0, 0.5 * r, 0.999 * r, 1.001 * r, 0.5 * (r + H), H, 2 * H}) {
      CPContact k = c0;
      capMeasure(k, remembered);
      const Real cap = std::max(remembered, r), used = std::min(H, cap);
      EXPECT_NEAR(k.hA + k.hB, used, 1e-18);
      EXPECT_NEAR(k.gap, r - used, 1e-18);                      // never below min(r - remembered, r - H)
      EXPECT_GE(k.gap, std::min(r - H, std::min(Real(0), r - remembered)) - 1e-18);
      EXPECT_NEAR(k.hA * c0.hB, k.hB * c0.hA, 1e-14 * c0.hA * c0.hB);  // shared as before
      const Vec3 pA = c0.point - (c0.hA + 0.5 * c0.gap) * c0.normal;
      EXPECT_LT((k.point - (pA + (k.hA + 0.5 * k.gap) * k.normal)).norm(), 1e-18);
      if (remembered >= H) { EXPECT_EQ(k.gap, c0.gap); }        // room enough: untouched, bit for bit
      // The cap holds for the rest of the step: sections measured again (after flattening) obey it.
      CPContact again = k;
      remeasure(f, again, SectionRule::ConstantArea, true);
      EXPECT_LE(again.hA + again.hB, k.hCap * (1 + 1e-15));
    }
  }
}

// Skew pieces side by side (10 degrees apart, an X seen from above, the axes 60 um apart at its
// centre): the ends of the shared part see the axes farther apart than they come, so the closest
// point must be one of the manifold's points, with the gap of the axes' true distance there.
TEST(GapFunction, SkewSideBySidePiecesHoldTheirClosestApproach) {
  std::mt19937_64 rng(22);
  const Real d = 60e-6, L = 0.4e-3, a = 10 * 3.14159265358979323846 / 180;
  const Vec3 u(std::cos(a), std::sin(a), 0);
  Fabric f = randomPair(rng, Vec3(-L, 0, 0), Vec3(L, 0, 0), Vec3(0, 0, d) - L * u, Vec3(0, 0, d) + L * u);
  CPContact c[2];
  ASSERT_EQ(pairGaps(f, 0, 1, true, SectionRule::ConstantArea, nullptr, c), 2);
  int atCentre = 0;
  for (int q = 0; q < 2; ++q) {
    EXPECT_EQ(c[q].kind, ContactKind::Side);
    if (std::abs(c[q].sA - 0.5) < 1e-9) {
      ++atCentre;
      EXPECT_NEAR(c[q].sB, 0.5, 1e-9);
      EXPECT_NEAR(c[q].gap + c[q].hA + c[q].hB, d, 1e-15);  // the axes' distance at the X's centre
    } else {
      EXPECT_GT(c[q].gap + c[q].hA + c[q].hB, d + 1e-6);    // an end: farther apart
    }
  }
  EXPECT_EQ(atCentre, 1);
  // Parallel pieces (no crossing inside): the two ends, as a line contact.
  Fabric g = randomPair(rng, Vec3(-L, 0, 0), Vec3(L, 0, 0), Vec3(-L, 0, d), Vec3(L, 0, d));
  ASSERT_EQ(pairGaps(g, 0, 1, true, SectionRule::ConstantArea, nullptr, c), 2);
  EXPECT_NEAR(std::min(c[0].sA, c[1].sA), 0.0, 1e-12);
  EXPECT_NEAR(std::max(c[0].sA, c[1].sA), 1.0, 1e-12);
}

// Side-by-side ends held by the segment end that makes them (SideAnchor): where B's ends lie
// alongside A, each end of the shared part is B's end with A's closest point to it, a
// vertex-segment distance (checked against the point-line distance computed here). Skew pieces
// slide the shared part along A as they move: the last step's contact measured again at the new
// positions (what its row and the projection act on) must equal the next narrow phase's end, so
// that sliding opens no gap between them (a point held at its place on A left 10-15 um a step).
TEST(GapFunction, SideBySideEndsAreHeldByTheEndsThatMakeThem) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<Real> angle(2, 18), gap(20e-6, 0.4e-3), shift(-0.2, 0.2), move(-20e-6, 20e-6);
  const Real L = 0.4e-3, deg = 3.14159265358979323846 / 180;
  int checked = 0;
  for (int n = 0; n < 2000; ++n) {
    const Real a = angle(rng) * deg, z = gap(rng), c0 = shift(rng) * L;
    const Vec3 u(std::cos(a), std::sin(a), 0), mid(c0, 0, z);
    Fabric f = randomPair(rng, Vec3(-L, 0, 0), Vec3(L, 0, 0), mid - 0.5 * L * u, mid + 0.5 * L * u);
    CPContact c[2];
    ASSERT_EQ(pairGaps(f, 0, 1, true, SectionRule::ConstantArea, nullptr, c), 2);
    const Vec3 eA = f.pos[1] - f.pos[0];
    for (int q = 0; q < 2; ++q) {
      if (c[q].anchor == SideAnchor::Closest) continue;  // an X inside the shared part
      ASSERT_EQ(c[q].anchor, SideAnchor::B);
      ASSERT_TRUE(c[q].sB == 0 || c[q].sB == 1);
      const Vec3 end = f.pos[2 + static_cast<Index>(c[q].sB)];
      const Real foot = (end - f.pos[0]).dot(eA) / eA.squaredNorm();
      EXPECT_NEAR(c[q].sA, foot, 1e-14);
      const Real r = (end - f.pos[0]).cross(eA).norm() / eA.norm();  // point-line distance
      EXPECT_NEAR(c[q].gap + c[q].hA + c[q].hB, r, 1e-15);
    }
    // B moves a little (a translation and a turn about its middle), the shared part slides.
    const Vec3 t(move(rng), move(rng), move(rng));
    const Real turn = 0.01 * move(rng) / 20e-6;
    const Vec3 m = 0.5 * (f.pos[2] + f.pos[3]);
    for (Index k = 2; k < 4; ++k) f.pos[k] = m + Eigen::AngleAxis<Real>(turn, Vec3::UnitZ()) * (f.pos[k] - m) + t;
    CPContact fresh[2];
    ASSERT_EQ(pairGaps(f, 0, 1, true, SectionRule::ConstantArea, nullptr, fresh), 2);
    for (int q = 0; q < 2; ++q) {
      if (c[q].anchor != SideAnchor::B || fresh[q].anchor != SideAnchor::B || fresh[q].sB != c[q].sB) continue;
      CPContact again = c[q];
      remeasure(f, again, SectionRule::ConstantArea, true);
      EXPECT_NEAR(again.sA, fresh[q].sA, 1e-14);
      EXPECT_NEAR(again.gap, fresh[q].gap, 1e-15) << "configuration " << n;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

// The narrow phase's chords, taken once per CP (ChordFrames), give the same contacts to the last bit
// as the chords taken pair by pair: 1e4 random pairs at any angle, both kinds, compared exactly.
TEST(GapFunction, ChordFramesGiveTheSameBitsAsChordsPairByPair) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 tA = randomUnit(rng), tB = randomUnit(rng);
    const Vec3 cA = 0.3e-3 * Vec3(u(rng), u(rng), u(rng)), cB = 0.3e-3 * Vec3(u(rng), u(rng), u(rng));
    Fabric f = randomPair(rng, cA - 0.4e-3 * tA, cA + 0.4e-3 * tA, cB - 0.3e-3 * tB, cB + 0.3e-3 * tB);
    ChordFrames chords;
    for (Index e = 0; e < 2; ++e) {
      const Vec3 d = f.pos[f.elem0[e] + 1] - f.pos[f.elem0[e]];
      chords.unit.push_back(d.normalized()), chords.length.push_back(d.norm());
    }
    for (bool was : {false, true}) ASSERT_EQ(sideBySide(f, 0, 1, was), sideBySide(f, 0, 1, was, &chords));
    const bool side = sideBySide(f, 0, 1, false);
    CPContact plain[2], framed[2];
    const int m = pairGaps(f, 0, 1, side, SectionRule::ConstantArea, nullptr, plain);
    ASSERT_EQ(pairGaps(f, 0, 1, side, SectionRule::ConstantArea, nullptr, framed, nullptr, nullptr, &chords), m);
    for (int q = 0; q < m; ++q) {
      EXPECT_EQ(plain[q].gap, framed[q].gap);
      EXPECT_EQ(plain[q].hA, framed[q].hA);
      EXPECT_EQ(plain[q].hB, framed[q].hB);
      EXPECT_EQ(plain[q].sA, framed[q].sA);
      EXPECT_EQ(plain[q].sB, framed[q].sB);
      EXPECT_TRUE(plain[q].normal == framed[q].normal && plain[q].hDir == framed[q].hDir);
    }
  }
}

// The section measure of crossing pieces is the two half-thicknesses at 45 degrees and beyond
// (GapFunction.hpp), exactly: just past 45 degrees (where the weight skips its arc cosine) and within
// 1e-10 rad of it, hA is A's minor semi-axis at the contact point to the last bit, not its support
// along the normal. Just below, the blend with the support starts (hA moves off b).
TEST(GapFunction, CrossingMeasureIsTheHalfThicknessFrom45Degrees) {
  std::mt19937_64 rng(22);
  const Vec3 tA = Vec3::UnitX(), up = Vec3::UnitZ();
  for (Real off : {1e-6, 1e-10, 0.0, -1e-3}) {
    const Real angle = M_PI / 4 + off;
    const Vec3 tB(std::cos(angle), std::sin(angle), 0);
    Fabric f = randomPair(rng, -0.4e-3 * tA, 0.4e-3 * tA, 0.2e-3 * up - 0.4e-3 * tB, 0.2e-3 * up + 0.4e-3 * tB);
    // Flattened (width 2.8 x thickness), A's minor axis tilted off the normal: its support along the
    // normal exceeds b by 60 %
    for (Index k = 0; k < 4; ++k) f.secDir[k] = k < 2 ? Vec3(0, 0.3, 1).normalized() : up, f.secFlat[k] = 0.4;
    CPContact c[2];
    ASSERT_EQ(pairGaps(f, 0, 1, false, SectionRule::ConstantArea, nullptr, c), 1);
    const Real b = sectionAt(f, 0, c[0].sA, SectionRule::ConstantArea).b;
    if (off >= 0) EXPECT_EQ(c[0].hA, b) << "45 deg + " << off;
    else EXPECT_GT(c[0].hA, b * (1 + 1e-6)) << "45 deg " << off;
  }
}

namespace {
// A body with one triangle part (edges about 1-3 mm) offset from its centre of mass and turned at
// random: a face of a mesh held by a clump, so that the arm of the row is tested too.
RigidBody randomTriangle(std::mt19937_64& rng, const Vec3& partCentre, bool twoSided) {
  std::uniform_real_distribution<Real> u(-1, 1);
  RigidBody b;
  RigidPart part;
  part.type = RigidPart::Type::Triangle, part.twoSided = twoSided;
  for (Vec3& v : part.vert) v = 1.5e-3 * Vec3(u(rng), u(rng), 0.2 * u(rng));
  part.offset = 0.5e-3 * randomUnit(rng);
  part.ori = Quat(Eigen::AngleAxis<Real>(3 * u(rng), randomUnit(rng)));
  b.parts.push_back(part);
  b.mass = 1e-3, b.inertia = Vec3::Constant(1e-9);
  b.ori = Quat(Eigen::AngleAxis<Real>(3 * u(rng), randomUnit(rng)));
  b.pos = partCentre - b.ori * part.offset;
  return b;
}

// Distance [m] from a point to segment (p0, p1), closed form.
Real pointSegment(const Vec3& x, const Vec3& p0, const Vec3& p1) {
  const Vec3 d = p1 - p0;
  const Real s = std::clamp((x - p0).dot(d) / d.squaredNorm(), Real(0), Real(1));
  return (x - p0 - s * d).norm();
}
}  // namespace

// A CP and a triangle part: the axis segment's closest point to the triangle, the section's support
// along the normal; its gradient in the nodes, the translation and the rotation is the row.
TEST(GapFunction, TriangleRowIsTheGradientOfTheGap) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0, faces = 0;
  Real worst = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 t = randomUnit(rng);
    RigidBody b = randomTriangle(rng, Vec3::Zero(), n % 2 == 1);
    // The CP's centre 0.3-0.8 mm off the triangle's plane on its outer side, over it or beyond its edges.
    const Vec3 normal = b.partAxes(0) * (b.parts[0].vert[1] - b.parts[0].vert[0]).cross(b.parts[0].vert[2] - b.parts[0].vert[0]).normalized();
    Vec3 along = 1.5e-3 * Vec3(u(rng), u(rng), u(rng));
    along -= along.dot(normal) * normal;
    const Vec3 c0 = (b.partVertex(0, 0) + b.partVertex(0, 1) + b.partVertex(0, 2)) / 3 + along +
                    (0.3e-3 + 0.5e-3 * std::abs(u(rng))) * normal;
    Fabric f = randomPair(rng, c0 - 0.4e-3 * t, c0 + 0.4e-3 * t, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    BodyContact c[2];
    const int m = bodyGap(f, 0, b, 0, 1.0, 1.0, SectionRule::ConstantArea, c);  // a huge reach: listed
    ASSERT_GE(m, 1) << "n " << n << " x0 " << f.pos[0].transpose() << " x1 " << f.pos[1].transpose() << " v "
                    << b.partVertex(0, 0).transpose() << " / " << b.partVertex(0, 1).transpose() << " / "
                    << b.partVertex(0, 2).transpose();
    for (int k = 0; k < m; ++k) {
      if (!(c[k].gap > 0)) continue;  // the CP through the plane: its own tests below
      faces += std::abs(std::abs(c[k].normal.dot(normal)) - 1) < 1e-12;
      bodyMatches(f, b, c[k], 1e-11, 1e-5, worst);
      ++tested;
    }
  }
  EXPECT_GT(tested, kConfigs / 2);
  EXPECT_GT(faces, kConfigs / 20) << "some configurations meet the face, not an edge or corner";
}

// For a circular section whose axis comes closest to an edge or corner of the triangle inside the CP, the gap is the
// distance between the CP's cylinder and the triangle: the axis segment's distance to the
// triangle minus the radius, the distance from a dense sampling of the triangle (301 x 301 points,
// about 10 um apart; its error is second order, under 1e-7 m at these distances) to the segment
// in closed form. An oracle that shares nothing with the Voronoi-region code.
TEST(GapFunction, TriangleGapIsTheSampledDistanceLessTheRadius) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<Real> u(-1, 1);
  int tested = 0;
  Real worst = 0;
  const long configs = runLength(400, 10);
  for (long n = 0; n < configs; ++n) {
    const Vec3 t = randomUnit(rng);
    RigidBody b = randomTriangle(rng, Vec3::Zero(), false);
    const Vec3 v[3] = {b.partVertex(0, 0), b.partVertex(0, 1), b.partVertex(0, 2)};
    const Vec3 normal = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
    const Vec3 c0 = (v[0] + v[1] + v[2]) / 3 + 1.5e-3 * Vec3(u(rng), u(rng), u(rng)) +
                    (0.4e-3 + 0.4e-3 * std::abs(u(rng))) * normal;
    Fabric f = randomPair(rng, c0 - 0.5e-3 * t, c0 + 0.5e-3 * t, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    for (Index k = 0; k < 2; ++k) f.secFlat[k] = 0;  // circular
    BodyContact c[2];
    // Only the edge and corner contacts: an end over the face is held along the face normal, where
    // the tilted disk reaches less than its radius.
    if (bodyGap(f, 0, b, 0, 1.0, 1.0, SectionRule::ConstantArea, c) != 1) continue;
    if (c[0].s < 0.02 || c[0].s > 0.98 || std::abs(c[0].normal.dot(t)) > 1e-9) continue;  // closest at an end
    Real D = INFINITY;
    const int N = 300;
    for (int i = 0; i <= N; ++i)
      for (int j = 0; i + j <= N; ++j) {
        const Vec3 y = v[0] + (v[1] - v[0]) * (Real(i) / N) + (v[2] - v[0]) * (Real(j) / N);
        D = std::min(D, pointSegment(y, f.pos[0], f.pos[1]));
      }
    const Real r = f.secRadius[0];
    worst = std::max(worst, std::abs(c[0].gap - (D - r)));
    EXPECT_NEAR(c[0].gap, D - r, 1e-6) << "n " << n;
    ++tested;
  }
  EXPECT_GT(tested, configs / 4);
  RecordProperty("largest_difference_m", std::to_string(worst));
}

// A CP under the face of a closed mesh (one-sided: the inside is behind it) is an overlap pushed out
// along the outward normal, held at both ends; under a lone facet (two-sided) it is outside, pushed
// the other way; an axis through a closed mesh's face is held at its end inside; an axis farther
// behind than a section's half-width is the far side of a thin solid, not in contact with this face.
TEST(GapFunction, TriangleSidesOfAClosedMeshAndOfALoneFacet) {
  RigidBody b;
  RigidPart p;
  p.type = RigidPart::Type::Triangle;
  p.vert[0] = Vec3(-2e-3, -2e-3, 0), p.vert[1] = Vec3(2e-3, -2e-3, 0), p.vert[2] = Vec3(0, 2e-3, 0);  // outward +z
  b.parts.push_back(p);
  b.mass = 1e-3, b.inertia = Vec3::Constant(1e-9);
  const auto gapOf = [&](const Vec3& a0, const Vec3& a1, bool twoSided, BodyContact& c) {
    std::mt19937_64 rng(1);
    Fabric f = randomPair(rng, a0, a1, Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
    for (Index k = 0; k < 2; ++k) f.secFlat[k] = 0, f.secDir[k] = Vec3::UnitZ();
    b.parts[0].twoSided = twoSided;
    BodyContact out[2];
    const int m = bodyGap(f, 0, b, 0, 1.0, 1.0, SectionRule::ConstantArea, out);
    EXPECT_EQ(m, 2);  // both ends over the face
    EXPECT_EQ(out[0].s, 0);
    EXPECT_EQ(out[1].s, 1);
    c = out[0];
    return f.secRadius[0];
  };
  BodyContact c;
  const Real r = gapOf(Vec3(-0.5e-3, 0, -20e-6), Vec3(0.5e-3, 0, -20e-6), false, c);
  EXPECT_NEAR(c.gap, -20e-6 - r, 1e-15);
  EXPECT_NEAR(c.normal.z(), -1, 1e-15);  // from the CP towards the body: the CP is pushed out along +z
  gapOf(Vec3(-0.5e-3, 0, -20e-6), Vec3(0.5e-3, 0, -20e-6), true, c);
  EXPECT_NEAR(c.gap, 20e-6 - r, 1e-15);
  EXPECT_NEAR(c.normal.z(), 1, 1e-15);
  // Through the face, 30 um of it inside at node 0: held there.
  gapOf(Vec3(-0.5e-3, 0, -30e-6), Vec3(0.5e-3, 0, 50e-6), false, c);
  EXPECT_EQ(c.s, 0);
  EXPECT_NEAR(c.normal.z(), -1, 1e-15);
  const Vec3 t = Vec3(1e-3, 0, 80e-6).normalized();  // the disk's reach along z: r |z - (z.t) t|
  EXPECT_NEAR(c.gap, -30e-6 - r * std::sqrt(1 - t.z() * t.z()), 1e-12);
  // 1 mm behind the face: no contact with it.
  std::mt19937_64 rng(1);
  Fabric f = randomPair(rng, Vec3(-0.5e-3, 0, -1e-3), Vec3(0.5e-3, 0, -1e-3), Vec3(5e-3, 0, 0), Vec3(6e-3, 0, 0));
  b.parts[0].twoSided = false;
  BodyContact out[2];
  EXPECT_EQ(bodyGap(f, 0, b, 0, 1e-9, 1e-6, SectionRule::ConstantArea, out), 0);
}
