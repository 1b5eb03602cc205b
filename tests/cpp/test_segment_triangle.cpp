// Segment-triangle closest points (geom/SegmentTriangle.hpp) against an independent brute-force
// oracle: the least distance over a dense sampling of the segment (kSeg + 1 points) and of the
// triangle (a barycentric grid of kTri subdivisions). The distance is 1-Lipschitz in either point, so
// the oracle exceeds the exact distance by at most the covering radii of the two samplings:
//   tol = L / (2 kSeg) + e_max / kTri   (L: segment length, e_max: longest triangle edge),
// and never falls below it (every sampled pair is a feasible pair). Configurations are drawn so that
// the closest triangle point lands on the face, on an edge and on a corner, and some segments cross.
#include "geom/SegmentTriangle.hpp"
#include <gtest/gtest.h>
#include <cmath>
#include <random>

using namespace woven;

namespace {

constexpr int kSeg = 100, kTri = 100, kConfigs = 400;

Real oracleDistance(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c) {
  std::vector<Vec3> tri;
  tri.reserve((kTri + 1) * (kTri + 2) / 2);
  for (int i = 0; i <= kTri; ++i)
    for (int j = 0; i + j <= kTri; ++j) {
      const Real u = Real(i) / kTri, v = Real(j) / kTri;
      tri.push_back((1 - u - v) * a + u * b + v * c);
    }
  Real best2 = std::numeric_limits<Real>::infinity();
  for (int k = 0; k <= kSeg; ++k) {
    const Vec3 p = p0 + (Real(k) / kSeg) * (p1 - p0);
    for (const Vec3& q : tri) best2 = std::min(best2, (p - q).squaredNorm());
  }
  return std::sqrt(best2);
}

}  // namespace

TEST(SegmentTriangle, MatchesSampledOracle) {
  std::mt19937_64 rng(20261207);
  std::uniform_real_distribution<Real> u(-1, 1);
  int counts[3] = {0, 0, 0}, crossings = 0;
  Real worstExcess = 0;
  for (int n = 0; n < kConfigs; ++n) {
    const Vec3 a(u(rng), u(rng), 0.2 * u(rng)), b(u(rng), u(rng), 0.2 * u(rng)), c(u(rng), u(rng), 0.2 * u(rng));
    if ((b - a).cross(c - a).norm() < 0.05) continue;  // keep the grid's covering radius bound honest
    std::uniform_real_distribution<Real> w(0.05, 1);
    auto inside = [&] {  // a random point well inside the triangle
      const Vec3 l(w(rng), w(rng), w(rng));
      return (l[0] * a + l[1] * b + l[2] * c) / l.sum();
    };
    const Vec3 up = (b - a).cross(c - a).normalized();
    Vec3 p0, p1;
    switch (n % 4) {
      case 0: {  // over the interior, nearly parallel to the plane: face region
        const Vec3 m = inside() + 0.3 * w(rng) * up;
        const Vec3 t = 0.05 * Vec3(u(rng), u(rng), u(rng));
        p0 = m - t, p1 = m + t + 0.02 * up;
        break;
      }
      case 1: p0 = inside() + w(rng) * up, p1 = inside() - w(rng) * up; break;  // crossing
      default: p0 = Vec3(1.5 * u(rng), 1.5 * u(rng), u(rng)), p1 = Vec3(2 * u(rng), 2 * u(rng), u(rng)); break;
    }
    const SegmentTriangleClosest r = closestSegmentTriangle(p0, p1, a, b, c);
    const Real oracle = oracleDistance(p0, p1, a, b, c);
    const Real emax = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const Real tol = (p1 - p0).norm() / (2 * kSeg) + emax / kTri;
    ASSERT_LE(r.distance, oracle + 1e-12) << "config " << n;
    ASSERT_LE(oracle - r.distance, tol) << "config " << n;
    worstExcess = std::max(worstExcess, (oracle - r.distance) / tol);
    // The reported points are the pair whose distance is reported, on the two sets.
    EXPECT_NEAR((r.onSegment - r.onTriangle).norm(), r.distance, 1e-12);
    EXPECT_GE(r.s, 0.0);
    EXPECT_LE(r.s, 1.0);
    EXPECT_NEAR(r.bary.sum(), 1.0, 1e-12);
    EXPECT_GE(r.bary.minCoeff(), -1e-12);
    if (r.distance == 0) ++crossings;
    else ++counts[int(r.feature)];
  }
  // Every region was exercised.
  EXPECT_GT(counts[int(TriangleFeature::Face)], 20);
  EXPECT_GT(counts[int(TriangleFeature::Edge)], 20);
  EXPECT_GT(counts[int(TriangleFeature::Corner)], 20);
  EXPECT_GT(crossings, 20);
  RecordProperty("worst_excess_over_tol", std::to_string(worstExcess));
}

TEST(SegmentTriangle, KnownRegions) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // Face: a segment parallel to the plane above the interior.
  auto r = closestSegmentTriangle(Vec3(0.1, 0.2, 0.3), Vec3(0.3, 0.2, 0.3), a, b, c);
  EXPECT_NEAR(r.distance, 0.3, 1e-15);
  EXPECT_EQ(r.feature, TriangleFeature::Face);
  // Edge: a segment crossing over the hypotenuse's outside, parallel to z.
  r = closestSegmentTriangle(Vec3(1, 1, -1), Vec3(1, 1, 1), a, b, c);
  EXPECT_NEAR(r.distance, std::sqrt(0.5), 1e-15);
  EXPECT_EQ(r.feature, TriangleFeature::Edge);
  EXPECT_NEAR(r.s, 0.5, 1e-15);
  // Corner: beyond vertex a.
  r = closestSegmentTriangle(Vec3(-1, -1, 0.5), Vec3(-2, -1, 0.5), a, b, c);
  EXPECT_NEAR(r.distance, std::sqrt(2.25), 1e-15);
  EXPECT_EQ(r.feature, TriangleFeature::Corner);
  EXPECT_EQ(r.s, 0.0);
  // Crossing through the face.
  r = closestSegmentTriangle(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 3), a, b, c);
  EXPECT_EQ(r.distance, 0.0);
  EXPECT_NEAR(r.s, 0.25, 1e-15);
  EXPECT_NEAR(r.onTriangle.x(), 0.2, 1e-15);
}
