// Closest points of two segments (Ericson, Real-Time Collision Detection, Sec. 5.1.9), robust for
// parallel and degenerate segments. Used for centre-line clearance and edge-edge contacts.
#pragma once
#include "core/Types.hpp"
#include <algorithm>

namespace woven {

struct SegmentClosest {
  Real s = 0, t = 0;   ///< parameters in [0, 1] on segment P and segment Q
  Real distance = 0;   ///< |P(s) - Q(t)| [m]
};

inline SegmentClosest closestSegmentSegment(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const Real a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const Real eps = 1e-300;
  Real s = 0, t = 0;
  if (a <= eps && e <= eps) {
    s = t = 0;
  } else if (a <= eps) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const Real c = d1.dot(r);
    if (e <= eps) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const Real b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  SegmentClosest out;
  out.s = s, out.t = t;
  out.distance = ((p0 + s * d1) - (q0 + t * d2)).norm();
  return out;
}

/// The point half way between the closest points `c` of segments P and Q.
inline Vec3 closestMidpoint(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, const SegmentClosest& c) {
  return 0.5 * ((1 - c.s) * p0 + c.s * p1 + (1 - c.t) * q0 + c.t * q1);
}

}  // namespace woven
