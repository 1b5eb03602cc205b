// Throughput of the chain dynamics, single thread: node-steps per second of FabricEngine::step on a
// fabric of ~1e6 nodes, next to a naive baseline with the same physics (array-of-structs nodes, a
// generic element list, separate zero / force / integrate passes). Both are first run side by side
// from the same state and must agree on the positions (to 1e-9 of the displacement).
//
//   bench_chain [nodes = 1000000] [seconds = 2]
//
// The fabric: sqrt(nodes) straight KM2 yarns of sqrt(nodes) nodes each, pre-stretched by 1e-3 with
// both ends fixed, and a seeded random velocity field small enough (strain ~6e-5) that no element
// goes slack, so every spring works on every step. dt = 0.9 dt_crit.
#include "core/Errors.hpp"
#include "engine/FabricEngine.hpp"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

using namespace woven;

namespace {

constexpr double kGoal = 50e6;  // node-steps per second, single thread

Fabric makeFabric(long nodes, std::vector<Index>& fixedNodes) {
  const int perYarn = std::max(2, static_cast<int>(std::lround(std::sqrt(static_cast<double>(nodes)))));
  const int yarns = std::max(1, static_cast<int>(nodes / perYarn));
  YarnMaterial m;  // KM2: E 90 GPa, rho 1440 kg/m^3, A 4.63e-8 m^2, tension only, undamped
  YarnSection s;
  const Real l0 = 0.1e-3, pitch = 0.75e-3, eps0 = 1e-3;
  Fabric f;
  Vec3Array pts(perYarn);
  for (int y = 0; y < yarns; ++y) {
    for (int i = 0; i < perYarn; ++i) pts[i] = Vec3(i * l0, y * pitch, 0);
    const Index yi = f.addYarn(pts, m, s, YarnFamily::Warp);
    fixedNodes.push_back(f.yarns[yi].firstNode);
    fixedNodes.push_back(f.yarns[yi].firstNode + f.yarns[yi].nNodes - 1);
  }
  std::mt19937 rng(12345);
  std::normal_distribution<Real> g(0.0, 0.5);  // 0.5 m/s: strain 0.5/c ~ 6e-5 << eps0
  for (Index i = 0; i < f.nNodes(); ++i) {
    f.pos[i].x() *= 1 + eps0;
    f.vel[i] = Vec3(g(rng), g(rng), g(rng));
  }
  for (Index i : fixedNodes) f.vel[i].setZero();
  return f;
}

// ---------------------------------------------------------------------------------------------
// Naive baseline: the textbook layout and loop structure, same physics as ChainDynamics.
struct Node {
  Vec3 x, v, f;
  Real m, invMass;
};
struct Element {
  Index a, b;
  Real l0, K, c;
  bool tensionOnly;
};

class Baseline {
 public:
  Baseline(const Fabric& fab, const std::vector<Index>& fixed) {
    nodes_.resize(fab.nNodes());
    for (Index i = 0; i < fab.nNodes(); ++i)
      nodes_[i] = Node{fab.pos[i], fab.vel[i], Vec3::Zero(), fab.mass[i], 1.0 / fab.mass[i]};
    for (Index i : fixed) nodes_[i].invMass = 0, nodes_[i].v.setZero();
    for (Index e = 0; e < fab.nElems(); ++e)
      elems_.push_back(Element{fab.elem0[e], fab.elem0[e] + 1, fab.restLength[e], fab.stiffness[e], fab.damping[e],
                               fab.materials[fab.yarns[fab.elemYarn[e]].material].tensionOnly});
    zeroForces();
    elementForces();
  }

  void step(Real dt) {
    integrate(dt);
    zeroForces();
    elementForces();
  }
  const std::vector<Node>& nodes() const { return nodes_; }

 private:
  void integrate(Real dt) {
    const Real hPrev = 0.5 * dtPrev_, h = 0.5 * dt;
    for (Node& n : nodes_) {
      const Vec3 a = n.f * n.invMass;  // kinematic nodes: invMass 0, velocity stays prescribed (0)
      const Vec3 vn = n.v + hPrev * a;
      n.v = vn + h * a;
      n.x += dt * n.v;
    }
    dtPrev_ = dt;
  }
  void zeroForces() {
    for (Node& n : nodes_) n.f.setZero();
  }
  void elementForces() {
    for (const Element& el : elems_) {
      Node &A = nodes_[el.a], &B = nodes_[el.b];
      const Vec3 d = B.x - A.x;
      const Real l = d.norm();
      const Vec3 n = d / l;
      const Real ldot = n.dot(B.v - A.v);
      const Real stretch = l - el.l0;
      Real T = el.K * stretch + el.c * ldot;
      if (el.tensionOnly) T = stretch > 0 ? std::max(T, 0.0) : 0.0;
      A.f += T * n;
      B.f -= T * n;
    }
  }

  std::vector<Node> nodes_;
  std::vector<Element> elems_;
  Real dtPrev_ = 0;
};

// ---------------------------------------------------------------------------------------------
template <class Step>
double rate(long nodes, double seconds, Step step, long& stepsDone) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  long steps = 0;
  double elapsed = 0;
  do {
    for (int k = 0; k < 10; ++k) step();
    steps += 10;
    elapsed = std::chrono::duration<double>(clock::now() - t0).count();
  } while (elapsed < seconds);
  stepsDone = steps;
  return static_cast<double>(nodes) * steps / elapsed;
}

}  // namespace

int main(int argc, char** argv) {
  const long target = argc > 1 ? std::atol(argv[1]) : 1000000;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 2.0;
  if (target < 4 || !(seconds > 0)) {
    std::fprintf(stderr, "usage: %s [nodes >= 4] [seconds > 0]\n", argv[0]);
    return 2;
  }
  std::vector<Index> fixed;
  const Fabric fabric = makeFabric(target, fixed);
  const long N = fabric.nNodes();
  std::printf("fabric: %d straight KM2 yarns, %ld nodes, %ld elements (pre-stretch 1e-3, both ends fixed)\n",
              fabric.nYarns(), N, static_cast<long>(fabric.nElems()));

  // --- same physics: run both a few steps from the same state and compare positions ---
  const int checkSteps = 20;
  Real dt = 0;
  {
    FabricEngine eng{Fabric(fabric)};
    for (Index i : fixed) eng.dynamics().fix(i);
    dt = 0.9 * eng.criticalDt();
    Baseline base(fabric, fixed);
    for (int k = 0; k < checkSteps; ++k) eng.step(dt), base.step(dt);
    Real maxDiff = 0, maxDisp = 0;
    for (long i = 0; i < N; ++i) {
      maxDiff = std::max(maxDiff, (eng.fabric().pos[i] - base.nodes()[i].x).norm());
      maxDisp = std::max(maxDisp, (eng.fabric().pos[i] - fabric.pos[i]).norm());
    }
    const Real relDiff = maxDiff / maxDisp;
    std::printf("check: after %d steps at dt = %.4g s (0.9 dt_crit): max |x_woven - x_baseline| = %.3g m, "
                "max displacement %.3g m, relative %.3g (required <= 1e-9): %s\n",
                checkSteps, dt, maxDiff, maxDisp, relDiff, relDiff <= 1e-9 ? "OK" : "MISMATCH");
    if (!(relDiff <= 1e-9)) return 1;
  }

  // --- throughput: windows of woven and baseline interleaved, so drifts in the machine's load and
  // memory bandwidth (large on a shared host) hit both alike; median and best of each are printed ---
  const int windows = 5;
  std::vector<double> wovenRates, baseRates;
  long wovenSteps = 0, baseSteps = 0;
  FabricEngine eng{Fabric(fabric)};
  for (Index i : fixed) eng.dynamics().fix(i);
  Baseline base(fabric, fixed);
  for (int w = 0; w < windows; ++w) {
    long s1 = 0, s2 = 0;
    try {
      wovenRates.push_back(rate(N, seconds / windows, [&] { eng.step(dt); }, s1));
    } catch (const InstabilityError& e) {
      std::printf("woven: %s\n", e.what());
      return 1;
    }
    baseRates.push_back(rate(N, seconds / windows, [&] { base.step(dt); }, s2));
    wovenSteps += s1, baseSteps += s2;
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double wovenRate = median(wovenRates), baseRate = median(baseRates);
  const double wovenBest = *std::max_element(wovenRates.begin(), wovenRates.end());
  const double baseBest = *std::max_element(baseRates.begin(), baseRates.end());
  std::printf("woven FabricEngine::step : median %8.2f, best %8.2f M node-steps/s  (%ld steps, %.2f ns per node-step)\n",
              wovenRate / 1e6, wovenBest / 1e6, wovenSteps, 1e9 / wovenRate);
  std::printf("naive AoS baseline       : median %8.2f, best %8.2f M node-steps/s  (%ld steps, %.2f ns per node-step)\n",
              baseRate / 1e6, baseBest / 1e6, baseSteps, 1e9 / baseRate);
  std::printf("ratio woven / baseline   : %8.2f (medians)\n", wovenRate / baseRate);
  std::printf("goal: >= %.0f M node-steps/s single thread (median): %s\n", kGoal / 1e6,
              wovenRate >= kGoal ? "met" : "NOT met");
  return 0;
}
