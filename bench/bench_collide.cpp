// Collision pipeline throughput on the tension scene (KM2 706, sections settled, warp ends pulled at
// 1 m/s), single thread, in CP-steps per second:
//   bench_collide [sizes = 10,30,100] [seconds per measurement = 3]
// For each size (yarns per family): the whole step with collisions (tree broad phase, default skin),
// the same with sweep and prune, the tree on 2 threads (woven::setThreads), and the chain alone (no
// collisions) as the baseline, with the
// collision stage's split (refit / broad / narrow / respond) and the ratios; then the two broad
// phases head to head with skin = 0 (a broad phase every step).
#include "core/Parallel.hpp"
#include "engine/FabricEngine.hpp"
#include "weave/WeaveBuilder.hpp"
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

using namespace woven;

namespace {

struct Run {
  double cpStepsPerSecond = 0;
  long steps = 0;
  CollisionStats stats;
  bool collisions = false;
};

std::unique_ptr<FabricEngine> scene(int yarns) {
  WeaveParams p = km2_706();
  p.nx = p.ny = yarns / 2;  // plain weave: 2 x 2 repeat
  p.warpMaterial.dampingRatio = p.weftMaterial.dampingRatio = 0.1;
  Weave w = buildWeave(p);
  auto e = std::make_unique<FabricEngine>(std::move(w.fabric));
  for (Index y : w.warpYarns) {
    const Yarn& Y = e->fabric().yarns[y];
    e->dynamics().fix(Y.firstNode);
    e->dynamics().prescribeVelocity(Y.firstNode + Y.nNodes - 1, Vec3(1, 0, 0));
  }
  return e;
}

Run measure(int yarns, bool collisions, BroadPhase broad, double seconds, Real skin = ContactParams().skin,
            int threads = 1) {
  setThreads(threads);  // the whole step, chain included
  auto e = scene(yarns);
  if (collisions) {
    ContactParams p;
    p.skin = skin;
    e->enableCollisions(p, broad);
    e->collisions()->settle(e->fabric());
  }
  const Real dt = 0.7 * e->criticalDt();
  for (int k = 0; k < 3; ++k) e->step(dt);  // warm up (tree build, buffers)
  if (collisions) e->collisions()->stats = CollisionStats();
  Run r;
  r.collisions = collisions;
  const auto t0 = std::chrono::steady_clock::now();
  double elapsed = 0;
  while (elapsed < seconds || r.steps < 3) {
    e->step(dt);
    ++r.steps;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  r.cpStepsPerSecond = double(e->fabric().nElems()) * r.steps / elapsed;
  if (collisions) r.stats = e->collisions()->stats;
  return r;
}

void printSplit(const char* name, const Run& r) {
  const double* s = r.stats.seconds;
  const double total = s[0] + s[1] + s[2] + s[3];
  std::printf("    %-5s collision stage per step: refit %.3g ms, broad %.3g ms, narrow %.3g ms, respond %.3g ms"
              " (%ld contacts, %ld candidates)\n",
              name, 1e3 * s[0] / r.steps, 1e3 * s[1] / r.steps, 1e3 * s[2] / r.steps, 1e3 * s[3] / r.steps,
              r.stats.contacts, r.stats.candidates);
  (void)total;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes{10, 30, 100};
  if (argc > 1) {
    sizes.clear();
    std::stringstream ss(argv[1]);
    for (std::string t; std::getline(ss, t, ',');) sizes.push_back(std::atoi(t.c_str()));
  }
  const double seconds = argc > 2 ? std::atof(argv[2]) : 3.0;
  std::printf("bench_collide: tension scene, KM2 706, cp_per_span 4, single thread, ~%.1f s per measurement\n", seconds);
  for (int n : sizes) {
    if (n < 2 || n % 2) {
      std::fprintf(stderr, "sizes: even yarn counts >= 2, got %d\n", n);
      return 2;
    }
    const Run chain = measure(n, false, BroadPhase::YarnTree, seconds);
    const Run tree = measure(n, true, BroadPhase::YarnTree, seconds);
    const Run sap = measure(n, true, BroadPhase::SweepAndPrune, seconds);
    auto e = scene(n);
    std::printf("%3d x %-3d yarns, %6d CPs:\n", n, n, e->fabric().nElems());
    std::printf("    chain only          %10.3g CP-steps/s (baseline)\n", chain.cpStepsPerSecond);
    std::printf("    collisions, tree    %10.3g CP-steps/s  (%.3g x the chain alone)\n", tree.cpStepsPerSecond,
                tree.cpStepsPerSecond / chain.cpStepsPerSecond);
    std::printf("    collisions, SAP     %10.3g CP-steps/s  (%.3g x the chain alone)\n", sap.cpStepsPerSecond,
                sap.cpStepsPerSecond / chain.cpStepsPerSecond);
    const Run tree2 = measure(n, true, BroadPhase::YarnTree, seconds, ContactParams().skin, 2);
    std::printf("    collisions, tree, 2 threads %10.3g CP-steps/s  (%.3g x one thread)\n",
                tree2.cpStepsPerSecond, tree2.cpStepsPerSecond / tree.cpStepsPerSecond);
    printSplit("tree", tree);
    printSplit("SAP", sap);
    std::printf("    broad phases run: tree %ld in %ld steps, SAP %ld in %ld steps (skin %.3g m)\n", tree.stats.broadPhases,
                tree.steps, sap.stats.broadPhases, sap.steps, ContactParams().skin);
    const Run tree0 = measure(n, true, BroadPhase::YarnTree, seconds / 2, 0);
    const Run sap0 = measure(n, true, BroadPhase::SweepAndPrune, seconds / 2, 0);
    const double bt = tree0.stats.seconds[1] / tree0.steps, bs = sap0.stats.seconds[1] / sap0.steps;
    std::printf("    broad phase every step (skin 0): tree %.3g ms, SAP %.3g ms, tree / SAP time = %.3g\n", 1e3 * bt,
                1e3 * bs, bt / bs);
  }
  return 0;
}
