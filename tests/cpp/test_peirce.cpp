// Peirce's plain-weave geometry (pkg/weave/Peirce.hpp): the solvers' output must satisfy Peirce's
// two relations, invert each other, reduce to the small-crimp limit c ~ (h/p)^2/2, and reject
// unreachable input with ParameterError.
#include "core/Errors.hpp"
#include "weave/Peirce.hpp"
#include "chain_util.hpp"
#include <gtest/gtest.h>
#include <cmath>
#include <functional>
#include <string>

using woven::PeirceState;
using woven::Real;

using woven_test::parameterOf;
using woven_test::rel;

namespace {

// Peirce's relations evaluated independently of the solver.
Real peirceP(const PeirceState& s) { return (s.l - s.D * s.theta) * std::cos(s.theta) + s.D * std::sin(s.theta); }
Real peirceH(const PeirceState& s) {
  return (s.l - s.D * s.theta) * std::sin(s.theta) + s.D * (1 - std::cos(s.theta));
}


const Real kP = 25.4e-3 / 34;  // KM2 spacing [m]
const Real kD = 0.22e-3;       // two 0.11 mm yarns [m]

}  // namespace

TEST(Peirce, FromHeightSatisfiesPeirceRelations) {
  // Spacings both wider and narrower than D; heights from nearly flat to close to the jam.
  for (Real p : {kP, 2 * kD, 0.8 * kD})
    for (Real frac : {1e-4, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9}) {
      // hmax as in the header: h(theta) at the largest admissible angle.
      const Real tmax = p >= kD ? 0.5 * M_PI * (1 - 1e-9) : std::asin(p / kD);
      const Real hmax = (p - kD * std::sin(tmax)) * std::tan(tmax) + kD * (1 - std::cos(tmax));
      const Real h = frac * std::min(hmax, 2 * kD);
      SCOPED_TRACE("p = " + std::to_string(p) + ", h = " + std::to_string(h));
      const PeirceState s = woven::peirceFromHeight(p, h, kD);
      EXPECT_EQ(s.p, p);
      EXPECT_EQ(s.D, kD);
      EXPECT_GT(s.theta, 0);
      EXPECT_GE(s.l - kD * s.theta, 0);  // straight part not negative
      // Bisection to machine precision: both relations hold to 1e-12 relative.
      EXPECT_LT(rel(peirceP(s), p), 1e-12);
      EXPECT_LT(rel(peirceH(s), h), 1e-12);
      EXPECT_LT(rel(s.crimp(), (s.l - p) / p), 1e-15);
    }
  // h = 0: straight yarn, l = p.
  const PeirceState flat = woven::peirceFromHeight(kP, 0, kD);
  EXPECT_EQ(flat.theta, 0);
  EXPECT_LT(rel(flat.l, kP), 1e-15);
}

TEST(Peirce, FromCrimpSatisfiesPeirceRelations) {
  for (Real p : {kP, 2 * kD})
    for (Real c : {1e-5, 1e-3, 0.0109, 0.05, 0.2}) {
      SCOPED_TRACE("p = " + std::to_string(p) + ", crimp = " + std::to_string(c));
      const PeirceState s = woven::peirceFromCrimp(p, c, kD);
      EXPECT_LT(rel(s.l, p * (1 + c)), 1e-15);  // definition of crimp
      EXPECT_LT(rel(peirceP(s), p), 1e-12);
      EXPECT_LT(rel(peirceH(s), s.h), 1e-12);
      // crimp() recovers c up to the cancellation in l - p: relative error ~ eps/c.
      EXPECT_LT(std::abs(s.crimp() - c), 1e-15 * (1 + c) * 4);
    }
}

TEST(Peirce, HeightToCrimpToHeightRoundTrip) {
  for (Real frac : {0.02, 0.2, 0.5, 1.0, 1.5}) {
    const Real h = frac * kD;
    const PeirceState a = woven::peirceFromHeight(kP, h, kD);
    const PeirceState b = woven::peirceFromCrimp(kP, a.crimp(), kD);
    // Conditioning: c carries a relative error ~eps/c (>= 1e-13 here for c >= 1e-3); h(c) ~ sqrt(c)
    // halves it. 1e-10 relative leaves a wide margin above that and catches any solver slip.
    EXPECT_LT(rel(b.h, h), 1e-10) << "h = " << h << ", crimp = " << a.crimp();
    EXPECT_LT(rel(b.theta, a.theta), 1e-10);
    EXPECT_LT(rel(b.l, a.l), 1e-12);
  }
}

TEST(Peirce, SmallCrimpLimitIsHalfTheSquaredSlope) {
  // Expanding Peirce's relations for small theta (l ~ p):
  //   p = l - l theta^2/2 + D theta^3/3,  h = l theta - D theta^2/2 - l theta^3/6
  //   => c = theta^2/2 - D theta^3/(3p),  (h/p)^2/2 = theta^2/2 - D theta^3/(2p)   (+ O(theta^4))
  // so (c - (h/p)^2/2)/c = D theta/(3p) + O(theta^2) -> 0 as h/p -> 0.
  Real previous = INFINITY;
  for (Real slope : {0.1, 0.03, 0.01, 0.003, 0.001}) {
    const Real h = slope * kP;
    const PeirceState s = woven::peirceFromHeight(kP, h, kD);
    const Real limit = 0.5 * slope * slope;
    const Real d = rel(s.crimp(), limit);
    SCOPED_TRACE("h/p = " + std::to_string(slope) + ": relative difference " + std::to_string(d));
    EXPECT_LT(d, previous);  // shrinks as h/p -> 0
    // Leading term D theta/(3p); the O(theta^2) remainder is bounded here by theta^2/2.
    EXPECT_LT(std::abs(d - kD * s.theta / (3 * kP)), 0.5 * s.theta * s.theta);
    previous = d;
  }
  EXPECT_LT(previous, 1e-3);
}

TEST(Peirce, BadInputNamesTheParameter) {
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(0, 1e-4, kD); }), "p");
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(-kP, 1e-4, kD); }), "p");
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(kP, 1e-4, 0); }), "D");
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(kP, -1e-6, kD); }), "h");
  // p < D: the largest height is reached at sin(theta) = p/D; above it is unreachable.
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(0.5 * kD, 10 * kD, kD); }), "h");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(0, 0.01, kD); }), "p");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(kP, 0.01, -kD); }), "D");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(kP, -0.01, kD); }), "crimp");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(kP, 1.0, kD); }), "crimp");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(kP, NAN, kD); }), "crimp");
  // Named as the Python arguments (p, h, D, crimp); infinities and NaN never pass (they came out as NaN).
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(INFINITY, 1e-4, kD); }), "p");
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(kP, NAN, kD); }), "h");
  EXPECT_EQ(parameterOf([] { woven::peirceFromHeight(kP, 1e-4, INFINITY); }), "D");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(NAN, 0.01, kD); }), "p");
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(kP, 0.01, 1e300); }), "D");
  // p = 0.1 D, c = 0.5: l = 0.15 D < D*pi/2 and even the shortest chord D sin(l/D) = 0.149 D > p.
  EXPECT_EQ(parameterOf([] { woven::peirceFromCrimp(0.1 * kD, 0.5, kD); }), "crimp");
}
