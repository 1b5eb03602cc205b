// Rigid projectiles for the tests: a cube and a ball of given size, mass, place and velocity, and a
// cube dropped onto a fabric (centred over it, a gap above its top).
#pragma once
#include "fabric/Fabric.hpp"
#include "shape/RigidBody.hpp"

namespace woven_test {

/// A cube of half edge `half` [m] and mass [kg] (inertia m (2 half)^2 / 6 about every axis).
inline woven::RigidBody cube(woven::Real half, woven::Real mass, const woven::Vec3& pos, const woven::Vec3& vel) {
  woven::RigidBody b;
  woven::RigidPart part;
  part.type = woven::RigidPart::Type::Box, part.halfSize = woven::Vec3::Constant(half);
  b.parts.push_back(part);
  b.mass = mass, b.inertia = woven::Vec3::Constant(mass * 4 * half * half / 6), b.pos = pos, b.vel = vel;
  return b;
}

/// A ball of radius r [m] and mass [kg] (inertia 2/5 m r^2).
inline woven::RigidBody ball(woven::Real r, woven::Real mass, const woven::Vec3& pos, const woven::Vec3& vel) {
  woven::RigidBody b;
  woven::RigidPart part;
  part.type = woven::RigidPart::Type::Sphere, part.radius = r;
  b.parts.push_back(part);
  b.mass = mass, b.inertia = woven::Vec3::Constant(0.4 * mass * r * r), b.pos = pos, b.vel = vel;
  return b;
}

/// cube() centred over the fabric's bounding box, `gap` [m] above its highest node.
inline woven::RigidBody cubeAbove(const woven::Fabric& f, woven::Real half, woven::Real mass, woven::Real gap,
                                  const woven::Vec3& vel) {
  woven::Vec3 lo = f.pos[0], hi = lo;
  for (const woven::Vec3& x : f.pos) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  return cube(half, mass, woven::Vec3(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), hi.z() + half + gap), vel);
}

}  // namespace woven_test
