// Closest points of a segment and a triangle in 3D, for the contact of a yarn's contact point (CP)
// axis segment with a mesh facet. The decomposition is Eberly's ("Distance Between a Line Segment and a
// Triangle", Geometric Tools, DistSegment3Triangle3): if the segment crosses the triangle the distance is
// zero at the crossing; otherwise both sets are convex, so the closest pair has a segment end point or a
// triangle edge point, and the answer is the least of the two end-point-vs-triangle distances (Ericson,
// Real-Time Collision Detection, Sec. 5.1.5, Voronoi regions of the triangle) and the three
// segment-vs-edge distances (SegmentDistance.hpp).
#pragma once
#include "core/Types.hpp"
#include "geom/SegmentDistance.hpp"
#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace woven {

/// Where on the triangle the closest point lies: its Voronoi feature, for the contact normal.
enum class TriangleFeature { Face, Edge, Corner };

struct SegmentTriangleClosest {
  Real s = 0;             ///< parameter in [0, 1] on the segment
  Vec3 bary{1, 0, 0};     ///< barycentric weights of the triangle point on (a, b, c)
  Vec3 onSegment{0, 0, 0}, onTriangle{0, 0, 0};
  Real distance = 0;      ///< |onSegment - onTriangle| [m]
  TriangleFeature feature = TriangleFeature::Face;
};

namespace detail {

/// Closest point of triangle (a, b, c) to p as barycentric weights (Ericson Sec. 5.1.5).
inline Vec3 closestPointTriangleBary(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const Real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const Real v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const Real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const Real w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const Real w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const Real denom = va + vb + vc;
  if (!(denom > 0)) return {1, 0, 0};  // degenerate (zero-area) triangle: the edge cases above cover it
  const Real v = vb / denom, w = vc / denom;
  return {1 - v - w, v, w};
}

inline TriangleFeature featureOf(const Vec3& bary) {
  const int zeros = (bary[0] == 0) + (bary[1] == 0) + (bary[2] == 0);
  return zeros == 0 ? TriangleFeature::Face : zeros == 1 ? TriangleFeature::Edge : TriangleFeature::Corner;
}

}  // namespace detail

inline SegmentTriangleClosest closestSegmentTriangle(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                                                     const Vec3& c) {
  SegmentTriangleClosest best;
  best.distance = std::numeric_limits<Real>::infinity();
  const Vec3 d = p1 - p0;
  auto consider = [&](Real s, const Vec3& bary) {
    const Vec3 ps = p0 + s * d, q = bary[0] * a + bary[1] * b + bary[2] * c;
    const Real dist = (ps - q).norm();
    if (dist < best.distance) {
      best.s = s, best.bary = bary, best.onSegment = ps, best.onTriangle = q, best.distance = dist;
      best.feature = detail::featureOf(bary);
    }
  };
  // Crossing: the end points on either side of the plane and the plane point inside the triangle.
  const Vec3 n = (b - a).cross(c - a);
  const Real h0 = n.dot(p0 - a), h1 = n.dot(p1 - a);
  if (n.squaredNorm() > 0 && ((h0 <= 0 && h1 >= 0) || (h0 >= 0 && h1 <= 0)) && h0 != h1) {
    const Real s = h0 / (h0 - h1);
    const Vec3 x = p0 + s * d;
    const Real nn = n.squaredNorm();
    const Real u = n.dot((c - b).cross(x - b)) / nn, v = n.dot((a - c).cross(x - c)) / nn;
    const Real w = 1 - u - v;
    if (u >= 0 && v >= 0 && w >= 0) {
      consider(s, Vec3(u, v, w));
      best.distance = 0;
      return best;
    }
  }
  consider(0, detail::closestPointTriangleBary(p0, a, b, c));
  consider(1, detail::closestPointTriangleBary(p1, a, b, c));
  const Vec3* v[3] = {&a, &b, &c};
  for (int e = 0; e < 3; ++e) {
    const int i = e, j = (e + 1) % 3;
    const SegmentClosest sc = closestSegmentSegment(p0, p1, *v[i], *v[j]);
    Vec3 bary = Vec3::Zero();
    bary[i] = 1 - sc.t, bary[j] = sc.t;
    consider(sc.s, bary);
  }
  return best;
}

}  // namespace woven
