// Random oriented boxes and an independent brute-force separating-axis reference for the narrow
// phase tests: projects the 8 vertices of both boxes on each of the 15 axes (no use of the
// closed-form radii in pkg/geom).
#pragma once
#include "bound/OBB.hpp"
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <random>

namespace woven_test {

using woven::Mat3;
using woven::OBB;
using woven::Real;
using woven::Vec3;

inline std::array<Vec3, 8> vertices(const OBB& b) {
  std::array<Vec3, 8> v;
  int k = 0;
  for (int s0 : {-1, 1})
    for (int s1 : {-1, 1})
      for (int s2 : {-1, 1}) v[k++] = b.vertex(s0, s1, s2);
  return v;
}

/// Penetration of the projections of a and b on unit axis n: the shorter of the two pushes that
/// separate the intervals, min(amax - bmin, bmax - amin) (negative: gap) [m].
inline Real projectedOverlap(const OBB& a, const OBB& b, const Vec3& n) {
  Real amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
  for (const Vec3& p : vertices(a)) amin = std::min(amin, p.dot(n)), amax = std::max(amax, p.dot(n));
  for (const Vec3& p : vertices(b)) bmin = std::min(bmin, p.dot(n)), bmax = std::max(bmax, p.dot(n));
  return std::min(amax - bmin, bmax - amin);
}

/// Brute-force minimum over the 15 axes (edge axes with sine < minSine skipped) of the projected
/// overlap; negative = separated by that much on the best separating axis.
inline Real bruteForceDepth(const OBB& a, const OBB& b, Real minSine = 1e-6) {
  Real best = INFINITY;
  for (int i = 0; i < 3; ++i) best = std::min(best, projectedOverlap(a, b, a.axis(i)));
  for (int j = 0; j < 3; ++j) best = std::min(best, projectedOverlap(a, b, b.axis(j)));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3 L = a.axis(i).cross(b.axis(j));
      if (L.norm() < minSine) continue;
      best = std::min(best, projectedOverlap(a, b, L.normalized()));
    }
  return best;
}

inline Mat3 randomRotation(std::mt19937& rng) {
  std::normal_distribution<Real> g(0, 1);
  Eigen::Quaternion<Real> q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// A random box: one in three is yarn-shaped (long and thin, like a CP's OBB), centre in a cube of
/// half-size `spread` [m].
inline OBB randomBox(std::mt19937& rng, Real spread) {
  std::uniform_real_distribution<Real> u(0, 1);
  OBB b;
  b.axes = randomRotation(rng);
  if (u(rng) < 1.0 / 3) b.extent = Vec3(0.5 + u(rng), 0.02 + 0.1 * u(rng), 0.01 + 0.05 * u(rng));
  else b.extent = Vec3(0.1 + u(rng), 0.1 + u(rng), 0.1 + u(rng));
  b.centre = spread * Vec3(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
  return b;
}

}  // namespace woven_test
