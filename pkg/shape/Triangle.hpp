// A triangle part (RigidPart::Type::Triangle): one face of a mesh, a YADE Facet or a face of a closed
// STL solid held by a rigid body. Convex, so its gap to a CP's section along a direction n is the
// separating-plane form of the box and the cylinder (geom/GapFunction: min over the part of y.n minus
// the section's reach), and min over a triangle of y.n is taken at a corner.
#pragma once
#include "bound/OBB.hpp"
#include "core/Types.hpp"
#include <algorithm>

namespace woven {

/// Flat box around the triangle (a, b, c) [m] (the broad phase's, and the bound tree's): axes the
/// longest edge, the in-plane normal to it and the face normal; a skin of 1e-9 m across the face
/// keeps the box solid.
inline OBB triangleBox(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e[3] = {b - a, c - b, a - c};
  int k = 0;
  for (int j = 1; j < 3; ++j)
    if (e[j].squaredNorm() > e[k].squaredNorm()) k = j;
  OBB box;
  const Vec3 n = e[0].cross(-e[2]);
  const Vec3 x = e[k].normalized(), z = n.squaredNorm() > 0 ? Vec3(n.normalized()) : x.unitOrthogonal();
  box.axes.col(0) = x, box.axes.col(1) = z.cross(x), box.axes.col(2) = z;
  const Vec3 p[3] = {box.axes.transpose() * a, box.axes.transpose() * b, box.axes.transpose() * c};
  const Vec3 lo = p[0].cwiseMin(p[1]).cwiseMin(p[2]), hi = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
  box.centre = box.axes * (0.5 * (lo + hi));
  box.extent = (0.5 * (hi - lo)).cwiseMax(Vec3::Constant(1e-9));
  return box;
}

/// min over the triangle (a, b, c) of y.n [m]: at a corner.
inline Real triangleMinAlong(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  return std::min({a.dot(n), b.dot(n), c.dot(n)});
}

}  // namespace woven
