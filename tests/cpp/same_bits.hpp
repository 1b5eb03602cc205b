// Same bits: the tests of restarts, snapshots and thread counts compare runs to the bit, never
// within a tolerance (a continued run is the straight run, or it is a defect).
#pragma once
#include "engine/FabricEngine.hpp"
#include <gtest/gtest.h>
#include <cstring>
#include <vector>

namespace woven_test {

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

/// Two engines after the same steps: the step count, the fabric's positions, velocities, sections
/// and broken elements, the energy books and the first rigid body's position, velocity and
/// orientation, all the same bits.
inline void expectSameRun(woven::FabricEngine& a, woven::FabricEngine& b) {
  using woven::Real, woven::Vec3;
  EXPECT_EQ(a.dynamics().stepCount(), b.dynamics().stepCount());
  EXPECT_TRUE(sameBits(a.fabric().pos, b.fabric().pos)) << "positions";
  EXPECT_TRUE(sameBits(a.fabric().vel, b.fabric().vel)) << "velocities";
  EXPECT_TRUE(sameBits(a.fabric().secFlat, b.fabric().secFlat)) << "sections";
  EXPECT_TRUE(sameBits(a.fabric().alive, b.fabric().alive)) << "broken elements";
  const woven::EnergyBooks x = a.dynamics().energy(), y = b.dynamics().energy();
  EXPECT_EQ(std::memcmp(&x, &y, sizeof(woven::EnergyBooks)), 0) << "energy books";
  const woven::RigidBody &p = a.collisions()->bodies[0], &q = b.collisions()->bodies[0];
  EXPECT_EQ(std::memcmp(p.pos.data(), q.pos.data(), sizeof(Vec3)), 0) << "body position";
  EXPECT_EQ(std::memcmp(p.vel.data(), q.vel.data(), sizeof(Vec3)), 0) << "body velocity";
  EXPECT_EQ(std::memcmp(p.ori.coeffs().data(), q.ori.coeffs().data(), 4 * sizeof(Real)), 0) << "body orientation";
}

}  // namespace woven_test
