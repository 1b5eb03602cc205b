// Binary state files (pkg/fabric/StateIO.hpp): a save/load round trip restores positions,
// velocities, step and time bit for bit, and a file of another fabric is refused.
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "fabric/StateIO.hpp"
#include "same_bits.hpp"
#include <gtest/gtest.h>
#include <cstdio>
#include <cstring>
#include <unistd.h>

using namespace woven_test;
using woven::FabricEngine;
using woven::KinematicState;

namespace {

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "woven_" + name + "_" + std::to_string(::getpid()) + ".state";
}

}  // namespace

TEST(StateIO, SaveLoadRoundTripIsBitForBit) {
  Fabric f = straightChain(64, 1e-3);
  randomVelocities(f, 8, 3.0);
  FabricEngine eng(std::move(f));
  const Real dt = 0.9 * eng.criticalDt();
  for (int k = 0; k < 37; ++k) eng.step(dt);  // arbitrary bits in every coordinate
  const KinematicState s = eng.state();
  static_assert(sizeof(Vec3) == 3 * sizeof(Real), "Vec3 is three packed doubles");

  const std::string path = tempPath("roundtrip");
  woven::saveState(path, s);
  const KinematicState r = woven::loadState(path, eng.fabric().nNodes());
  EXPECT_TRUE(sameBits(r.pos, s.pos));
  EXPECT_TRUE(sameBits(r.vel, s.vel));
  EXPECT_EQ(r.step, 37);
  EXPECT_EQ(std::memcmp(&r.time, &s.time, sizeof(Real)), 0);

  // Loaded into a fresh engine of the same fabric, the state is the saved one, bit for bit.
  FabricEngine other(straightChain(64, 1e-3));
  other.setState(r);
  EXPECT_TRUE(sameBits(other.fabric().pos, s.pos));
  EXPECT_TRUE(sameBits(other.fabric().vel, s.vel));
  std::remove(path.c_str());
}

TEST(StateIO, FileOfAnotherFabricIsRefused) {
  FabricEngine eng(straightChain(10, 1e-3));
  const std::string path = tempPath("other");
  woven::saveState(path, eng.state());  // 11 nodes
  EXPECT_EQ(parameterOf([&] { woven::loadState(path, 12); }), "state");
  EXPECT_NO_THROW(woven::loadState(path, 11));
  EXPECT_NO_THROW(woven::loadState(path));  // no expectation given
  FabricEngine bigger(straightChain(11, 1e-3));
  EXPECT_EQ(parameterOf([&] { bigger.setState(woven::loadState(path)); }), "state");
  std::remove(path.c_str());
  // A missing file names the path, a malformed one the state.
  EXPECT_EQ(parameterOf([&] { woven::loadState(path); }), "path");
  {
    std::FILE* out = std::fopen(path.c_str(), "wb");
    ASSERT_NE(out, nullptr);
    std::fputs("NOTASTATEFILE-----------------------", out);
    std::fclose(out);
  }
  EXPECT_EQ(parameterOf([&] { woven::loadState(path); }), "state");
  std::remove(path.c_str());
}
