// Narrow phase against ODE's box-box collider (Debian's libode as the oracle)
// on 1e5 random pairs, a third yarn-shaped: dBoxTouchesBox and dBoxBox say overlap exactly when we do
// (pairs within 1e-9 m of touching excepted), and ODE's depth lies in [ours, 1.05 * ours]: ours is
// the exact 15-axis minimum, ODE prefers a face axis unless an edge axis is 5 % shallower
// (physics-reference.md, "Box-box reference libraries").
#include "box_util.hpp"
#include "chain_util.hpp"
#include "geom/SeparatingAxis.hpp"
#include <gtest/gtest.h>
#include <ode/ode.h>

using namespace woven;
using namespace woven_test;

namespace {
struct OdeBox {
  dVector3 p, side;
  dMatrix3 R;
  explicit OdeBox(const OBB& b) {
    for (int i = 0; i < 3; ++i) {
      p[i] = b.centre[i];
      side[i] = 2 * b.extent[i];  // ODE takes full side lengths
      for (int j = 0; j < 3; ++j) R[i * 4 + j] = b.axes(i, j);  // box axes are R's columns
      R[i * 4 + 3] = 0;
    }
  }
};
}  // namespace

TEST(OdeOracle, OverlapAgreesAndDepthIsTheExactMinimum) {
  static_assert(sizeof(dReal) == sizeof(double), "Debian's libode is double precision");
  dInitODE();
  std::mt19937 rng(5);
  const int pairs = static_cast<int>(runLength(100000, 10));
  int compared = 0, deeperByFacePreference = 0;
  for (int k = 0; k < pairs; ++k) {
    const OBB a = randomBox(rng, 1.0), b = randomBox(rng, 1.0);
    const BoxContact c = obbContact(a, b);
    const OdeBox A(a), B(b);
    dVector3 normal;
    dReal depth;
    int code;
    dContactGeom contacts[8];
    const int n = dBoxBox(A.p, A.R, A.side, B.p, B.R, B.side, normal, &depth, &code, 8, contacts, sizeof(dContactGeom));
    const int touches = dBoxTouchesBox(A.p, A.R, A.side, B.p, B.R, B.side);
    if (std::abs(bruteForceDepth(a, b)) <= 1e-9) continue;  // touching within 1e-9 m
    ASSERT_EQ(c.overlap, n > 0) << "pair " << k;
    ASSERT_EQ(c.overlap, touches != 0) << "pair " << k;
    if (!c.overlap) continue;
    ++compared;
    EXPECT_GE(depth, c.depth * (1 - 1e-9)) << "pair " << k << ": ODE found a shallower axis";
    EXPECT_LE(depth, c.depth * 1.05 * (1 + 1e-9)) << "pair " << k;
    deeperByFacePreference += depth > c.depth * (1 + 1e-9);
  }
  dCloseODE();
  EXPECT_GT(compared, pairs / 10);
  EXPECT_GT(deeperByFacePreference, 0);  // the documented bias is seen, so the comparison has teeth
}
