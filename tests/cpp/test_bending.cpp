// Yarn bending (YarnMaterial::bending, ChainDynamics' discrete node-angle energy) against the
// Euler-Bernoulli beam in closed form: a simply supported chain released from its first mode's shape
// oscillates at omega_1 = (pi / L)^2 sqrt(EI / (rho A)) (discretisation error (pi h / L)^2 / 12 at
// 40 elements: 5e-4), keeps its energy books closed, and steps stably at 0.9 of the critical step,
// which the bending stiffness lowers.
#include "chain_util.hpp"
#include "dynamics/ChainDynamics.hpp"
#include "engine/FabricEngine.hpp"
#include <gtest/gtest.h>
#include <cmath>

using woven::FabricEngine;
using namespace woven_test;

namespace {
struct BeamRun {
  Real omega = 0;       // measured from the mid node's zero crossings [rad/s]
  Real balance = 0;     // largest |balance error| of the books / initial energy
  Real dtCrit = 0;
};

BeamRun pinnedBeam(Real EI, int N, Real L, Real amplitude, int halfPeriods) {
  YarnMaterial m = km2Material();
  m.bending = EI;
  Fabric f = straightChain(N, L / N, m);
  for (Index i = 0; i < f.nNodes(); ++i) f.pos[i].y() = amplitude * std::sin(M_PI * f.pos[i].x() / L);
  FabricEngine eng(std::move(f));
  auto& dyn = eng.dynamics();
  dyn.fix(0), dyn.fix(N);  // pinned: the end nodes hold their place, no moment (no bending term there)
  BeamRun r;
  r.dtCrit = eng.criticalDt();
  const Real dt = 0.9 * r.dtCrit;
  const Real E0 = dyn.energy().kinetic + dyn.energy().elastic;
  const Fabric& fab = eng.fabric();
  const Index mid = N / 2;
  Real prev = fab.pos[mid].y(), first = -1, last = -1;
  int crossings = 0;
  for (long n = 1; n < 10000000 && crossings <= halfPeriods; ++n) {
    eng.step(dt);
    const Real y = fab.pos[mid].y();
    if ((prev > 0) != (y > 0)) {  // a zero crossing, placed by linear interpolation
      const Real t = (n - 1 + prev / (prev - y)) * dt;
      if (crossings == 0) first = t;
      last = t;
      ++crossings;
    }
    prev = y;
    r.balance = std::max(r.balance, std::abs(dyn.energy().balanceError()) / E0);
  }
  if (crossings > 1) r.omega = M_PI * (crossings - 1) / (last - first);
  return r;
}
}  // namespace

TEST(Bending, SimplySupportedChainOscillatesAtTheBeamsFirstMode) {
  const Real EI = 1e-4, L = 0.01, rhoA = km2Material().rho * km2Material().area;
  const BeamRun r = pinnedBeam(EI, 40, L, 1e-6, 6);
  const Real omega = (M_PI / L) * (M_PI / L) * std::sqrt(EI / rhoA);
  ASSERT_GT(r.omega, 0);
  EXPECT_NEAR(r.omega / omega, 1.0, 0.01) << "measured " << r.omega << " rad/s, beam " << omega;
  EXPECT_LT(r.balance, 1e-3);
  RecordProperty("omega_ratio", std::to_string(r.omega / omega));
}

TEST(Bending, StiffnessLowersTheCriticalStepAndIsRefusedOutOfRange) {
  const Real L = 0.01;
  const BeamRun stiff = pinnedBeam(1e-2, 40, L, 1e-6, 2);  // omega^2 of bending above the axial one's
  YarnMaterial m = km2Material();
  const Real dtAxial = woven::criticalTimeStep(straightChain(40, L / 40, m));
  EXPECT_LT(stiff.dtCrit, dtAxial);
  EXPECT_NEAR(stiff.omega / ((M_PI / L) * (M_PI / L) * std::sqrt(1e-2 / (m.rho * m.area))), 1.0, 0.01);
  m.bending = 2;
  EXPECT_EQ(parameterOf([&] { m.validate(); }), "bending");
  m.bending = -1e-9;
  EXPECT_EQ(parameterOf([&] { m.validate(); }), "bending");
}
