// Energy conservation of the undamped chain (c = 0): a taut string vibrating transversally and
// axially keeps kinetic + elastic energy without secular drift, and the error that velocity Verlet
// does make is its known bounded O(dt^2) oscillation, checked against the scheme's modified energy.
#include "chain_util.hpp"
#include "dynamics/ChainDynamics.hpp"
#include "engine/FabricEngine.hpp"
#include <gtest/gtest.h>
#include <cmath>

using namespace woven_test;
using woven::FabricEngine;

TEST(DynamicsEnergy, UndampedTautStringConservesEnergy) {
  const int N = 49;  // 50 nodes
  const Real l0 = 1e-3, eps0 = 1e-3;
  const YarnMaterial m = km2Material(0.0);
  Fabric f = straightChain(N, l0, m);
  const Real c = std::sqrt(m.E / m.rho);
  for (Vec3& x : f.pos) x.x() *= 1 + eps0;  // pre-stretch: taut string
  // Smooth field: transverse modes 1 and 3 with about the kinetic energy of the pre-stretch
  // (amplitude c*eps0: the string swings to slopes ~0.04, geometrically non-linear), axial mode 2
  // with strain amplitude 0.5 m/s / c = 6e-5 < eps0, so no element goes slack.
  const Real vt = c * eps0, va = 0.5;
  for (Index i = 0; i <= N; ++i) {
    const Real s = Real(i) / N;
    f.vel[i] = Vec3(va * std::sin(2 * M_PI * s), vt * std::sin(M_PI * s), 0.5 * vt * std::sin(3 * M_PI * s));
  }
  FabricEngine eng(std::move(f));
  auto& dyn = eng.dynamics();
  dyn.fix(0);
  dyn.fix(N);
  dyn.refreshForces();  // forces of the initial state, for the correction below
  const Real dt = 0.9 * eng.criticalDt();
  const Fabric& fab = eng.fabric();

  // Backward error analysis of velocity Verlet (Hairer, Lubich, Wanner, Geometric Numerical
  // Integration, Ch. IX): the scheme conserves, to O(dt^4), the modified energy
  //   H~ = H + dt^2/12 v.Hess(V).v - dt^2/24 grad(V).M^-1.grad(V)
  // at the integer steps. For a spring, w.Hess.w = K (n.w)^2 + (T/l)(|w|^2 - (n.w)^2), w the
  // relative velocity of its nodes. So E_n = H oscillates by the dt^2 term and nothing else.
  auto correction = [&] {
    Real hess = 0, grad = 0;
    for (Index e = 0; e < fab.nElems(); ++e) {
      const Index a = fab.elem0[e];
      const Vec3 d = fab.pos[a + 1] - fab.pos[a];
      const Real l = d.norm();
      const Vec3 n = d / l, w = dyn.syncVelocity(a + 1) - dyn.syncVelocity(a);
      const Real wn = n.dot(w), T = fab.stiffness[e] * (l - fab.restLength[e]);
      hess += fab.stiffness[e] * wn * wn + T / l * (w.squaredNorm() - wn * wn);
    }
    for (Index i = 0; i < fab.nNodes(); ++i) grad += fab.invMass[i] * fab.force[i].squaredNorm();  // free nodes
    return dt * dt / 12 * hess - dt * dt / 24 * grad;
  };
  const auto b0 = dyn.energy();
  const Real E0 = b0.kinetic + b0.elastic;
  ASSERT_GT(b0.kinetic, 0.5 * b0.elastic);  // the motion carries a good share of the energy
  const Real corr0 = correction();

  const long steps = runLength(100000, 10);
  // Least-squares line through (n, E_n - E0), accumulated on the fly.
  Real sn = 0, sE = 0, snn = 0, snE = 0;
  Real maxModErr = 0, maxBalance = 0, maxBooks = 0, maxCorrChange = 0, minStrain = INFINITY;
  for (long n = 1; n <= steps; ++n) {
    eng.step(dt);
    const auto b = dyn.energy();
    const Real E = b.kinetic + b.elastic, corr = correction();
    sn += n, sE += E - E0, snn += Real(n) * n, snE += n * (E - E0);
    maxModErr = std::max(maxModErr, std::abs((E + corr) - (E0 + corr0)));
    maxCorrChange = std::max(maxCorrChange, std::abs(corr - corr0));
    maxBalance = std::max(maxBalance, std::abs(b.balanceError()));
    maxBooks = std::max({maxBooks, std::abs(b.damped), std::abs(b.work)});
    if (n % 100 == 0) {
      dyn.refreshForces();
      for (Real s : fab.strain) minStrain = std::min(minStrain, s);
    }
  }
  const Real slope = (steps * snE - sn * sE) / (steps * snn - sn * sn);  // [J per step]
  const Real drift = std::abs(slope) * steps / E0;
  EXPECT_LT(drift, 1e-6) << "relative energy drift over " << steps << " steps";
  EXPECT_GT(minStrain, 0.0) << "an element went slack: not a taut string";
  // No dashpots, fixed supports: nothing dissipated, no work done (0 up to rounding).
  EXPECT_LE(maxBooks, 1e-12 * E0);
  // The modified energy holds to O(dt^4): ~1e-8 of E0 here (16x less at dt/2); any dissipative or
  // anti-dissipative slip of the scheme would accumulate with the step count and break 1e-6.
  EXPECT_LT(maxModErr, 1e-6 * E0);
  // The balance error is the bounded dt^2 oscillation: within its size (+ the O(dt^4) rest).
  EXPECT_LT(maxBalance, maxCorrChange + 1e-6 * E0) << "max |balance error| / E0 = " << maxBalance / E0;
  EXPECT_LT(maxCorrChange, 1e-3 * E0);  // ~ (omega dt)^2/12 of the excited modes' energy
}
