// The default impact (scene=impact) or the tension scene (scene=tension), with no YADE. Impact:
// scripts/ballistic.py's scene built from the C++ core: a KM2 706
// ply clamped on its four edges, breakage on, struck at its centre by a rigid cube (shape/RigidBody:
// 5.59 mm, 1.1 g, 200 m/s, 50 um above the ply), the scene's contact settings (grid broad phase, skin
// 40 um, one flattening pass, 20 sweeps: scripts/ballistic.py's). Prints the time by phase of the collision stage, the
// CP-step rate against the springs alone (the same ply, collisions and breakage off, the fastest of
// three runs, in this process), the solve's figures and the run's outcome; with several thread counts
// the speed-up of each against one thread beside an ideal loop's (core/ThreadCeiling.hpp), and
// whether every count ends in the same bits (positions, velocities, sections and their directions,
// broken CPs, energy books, the cube), and with more than one thread what moving data between two
// threads costs (core/ThreadCeiling.hpp's coreHandoff). Tension: scripts/bench_threads.py's scene (bench_collide's):
// `yarns` x `yarns` yarns of KM2 706 (plain weave, cp 4 per span, damping ratio 0.1), sections settled,
// warp ends held and pulled along +x at 1 m/s (ramped over 10 us), collisions with the core's defaults
// (tree broad phase, sequential sweeps); its steps after `warmup` steps (trees, buffers) are timed.
// Sizes: side=0.0508 is 9 384 CPs, 0.166 about 1e5, 0.52 about 0.97e6 (2.9 GB; ~17 s to build on one
// thread); yarns=100 is 80 000 CPs, 200 is 320 000.
//   bench_impact [key=value ...]
//     scene=impact|tension   yarns=100 (tension: per family, even)   steps=0 (N > 0: N steps instead of t_end)
//     warmup=-1 (untimed steps first; -1: 0 for impact, 2 for tension)   sweep_order=default|sequential|coloured|blocked
//     side=0.0508 [m]   cp=1 (CPs per span)   t_end=1e-4 [s]   V=200 [m/s]   crossings=persistent|chords   skin=4e-5 [m]
//     threads=1 (comma-separated counts, e.g. 1,2,4,8,16)   sweeps=20   out=FILE (JSON of the figures)
//     baseline=1 (0: no springs-alone runs; for instruction counts of the coupled run alone)
//     every=0 (N > 0: lines every N steps with the wall time per step, the counts then and the census of
//              the contacts no crossing stands for: side by side, between near-parallel CPs)
// The step is FabricEngine::step (the engine adapter's work without YADE's own). Built with
// -DWOVEN_BASELINE against an earlier tree's core (bench/baseline_impact.sh), it runs that core's
// model on the same scene: paired runs of the persistent-crossing change.
#include "core/Parallel.hpp"
#include "core/ThreadCeiling.hpp"
#include "engine/FabricEngine.hpp"
#include "weave/WeaveBuilder.hpp"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace woven;

namespace {

struct Options {
  Real side = 0.0508, tEnd = 1e-4, V = 200, safety = 0.7, skin = 4e-5;
  int cp = 1, sweeps = 20;
  bool baseline = true;
  int every = 0;
  std::string scene = "impact", sweepOrder = "default";
  int yarns = 100, warmup = -1;
  long steps = 0;
  std::string crossings = "persistent", out;
  std::vector<int> threads = {1};
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr, "bench_impact: %s\n  keys: scene impact|tension, yarns [2, 2000] even, steps [0, 1e7], warmup [-1, 1e4], "
               "sweep_order default|sequential|coloured|blocked, side (0, 1] m, cp [1, 8], t_end (0, 1e-3] s, V (0, 5000] m/s, "
               "crossings persistent|chords, threads c1,c2,... in [1, 256], sweeps [1, 1000], skin [0, 0.01] m, baseline 0|1, every [0, 1e6] steps, out FILE\n", why.c_str());
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    const auto eq = a.find('=');
    if (eq == std::string::npos) usage("'" + a + "' is not key=value");
    const std::string key = a.substr(0, eq), v = a.substr(eq + 1);
    char* end = nullptr;
    const auto num = [&](Real lo, Real hi) {
      const Real x = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end || !(x > lo && x <= hi)) usage(key + " = " + v + " is out of range");
      return x;
    };
    if (key == "side") o.side = num(0, 1);
    else if (key == "cp") o.cp = static_cast<int>(num(0, 8));
    else if (key == "t_end") o.tEnd = num(0, 1e-3);
    else if (key == "V") o.V = num(0, 5000);
    else if (key == "sweeps") o.sweeps = static_cast<int>(num(0, 1000));
    else if (key == "baseline") o.baseline = num(-1, 1) > 0;
    else if (key == "skin") o.skin = num(-1, 1e-2);
    else if (key == "every") o.every = static_cast<int>(num(-1, 1e6));
    else if (key == "yarns") {
      o.yarns = static_cast<int>(num(1, 2000));
      if (o.yarns % 2) usage("yarns = " + v + " is invalid: an even count (the plain weave's 2 x 2 repeat)");
    } else if (key == "steps") o.steps = static_cast<long>(num(-1, 1e7));
    else if (key == "warmup") o.warmup = static_cast<int>(num(-2, 1e4));
    else if (key == "scene") {
      if (v != "impact" && v != "tension") usage("scene = " + v + " is invalid: impact or tension");
      o.scene = v;
    } else if (key == "sweep_order") {
      if (v != "default" && v != "sequential" && v != "coloured" && v != "blocked")
        usage("sweep_order = " + v + " is invalid: default, sequential, coloured or blocked");
      o.sweepOrder = v;
    } else if (key == "crossings") {
      if (v != "persistent" && v != "chords") usage("crossings = " + v + " is invalid: persistent or chords");
      o.crossings = v;
    } else if (key == "threads") {
      o.threads.clear();
      std::stringstream ss(v);
      for (std::string t; std::getline(ss, t, ',');) {
        const int n = std::atoi(t.c_str());
        if (n < 1 || n > 256) usage("threads = " + v + " is out of range");
        o.threads.push_back(n);
      }
      if (o.threads.empty()) usage("threads is empty");
    } else if (key == "out") o.out = v;
    else usage("unknown key '" + key + "'");
  }
  if (o.warmup < 0) o.warmup = o.scene == "tension" ? 2 : 0;
  return o;
}

// The scene's ply (woven.ballistic.build_ply): whole pattern repeats of KM2 706 filling `side`.
std::unique_ptr<FabricEngine> ply(const Options& o, bool collisions, bool breakage) {
  WeaveParams p = km2_706();
  p.cpPerSpan = o.cp;
  p.nx = p.ny = std::max(1, static_cast<int>(std::lround(o.side / p.weftSpacing / 2)));
  Weave w = buildWeave(p);
  auto e = std::make_unique<FabricEngine>(std::move(w.fabric));
  if (collisions) {
    ContactParams c;
    c.positionCorrection = 0, c.flattenPasses = 1, c.maxIterations = o.sweeps, c.skin = o.skin;
#ifndef WOVEN_BASELINE
    c.crossings = crossingsByName(o.crossings);
    if (o.sweepOrder != "default") c.sweepOrder = sweepOrderByName(o.sweepOrder);
#endif
    e->enableCollisions(c, BroadPhase::Grid);
    e->collisions()->settle(e->fabric());
  }
  for (const Yarn& y : e->fabric().yarns) e->dynamics().fix(y.firstNode), e->dynamics().fix(y.firstNode + y.nNodes - 1);
  if (breakage) {
    BreakageParams b;
    b.enabled = true;
    e->dynamics().configureBreakage(b);
  }
  return e;
}

// The cube above the ply's centre, its lowest face 50 um above the ply's top (the sections' reach).
void addCube(FabricEngine& e, Real V) {
  const Fabric& f = e.fabric();
  Vec3 lo = Vec3::Constant(INFINITY), hi = -lo;
  Real top = -INFINITY;
  for (Index k = 0; k < f.nNodes(); ++k) {
    lo = lo.cwiseMin(f.pos[k]), hi = hi.cwiseMax(f.pos[k]);
    top = std::max(top, f.pos[k].z() + semiAxes(f.secRadius[k], f.secFlat[k], e.collisions()->params().rule).b);
  }
  RigidBody b;
  RigidPart cube;
  const Real half = 0.5 * 5.59e-3, mass = 1.1e-3;
  cube.halfSize = Vec3::Constant(half);
  b.parts.push_back(cube);
  b.mass = mass, b.inertia = Vec3::Constant(mass * 4 * half * half / 6);
  b.pos = Vec3(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), top + half + 5e-5);
  b.vel = Vec3(0, 0, -V);
  e.collisions()->bodies.push_back(b);
}

// The tension scene (scripts/bench_threads.py): yarns x yarns yarns, warp ends held and pulled at 1 m/s.
std::unique_ptr<FabricEngine> tension(const Options& o, bool collisions) {
  WeaveParams p = km2_706();
  p.nx = p.ny = o.yarns / 2;  // plain weave: 2 x 2 repeat
  p.warpMaterial.dampingRatio = p.weftMaterial.dampingRatio = 0.1;
  Weave w = buildWeave(p);
  auto e = std::make_unique<FabricEngine>(std::move(w.fabric));
  if (collisions) {
    ContactParams c;
#ifndef WOVEN_BASELINE
    if (o.sweepOrder != "default") c.sweepOrder = sweepOrderByName(o.sweepOrder);
#endif
    e->enableCollisions(c, BroadPhase::YarnTree);
    e->collisions()->settle(e->fabric());
  }
  for (Index y : w.warpYarns) {
    const Yarn& Y = e->fabric().yarns[y];
    e->dynamics().fix(Y.firstNode);
    e->dynamics().prescribeVelocity(Y.firstNode + Y.nNodes - 1, Vec3(1, 0, 0));
  }
  e->dynamics().setVelocityRamp(1e-5);
  return e;
}

std::unique_ptr<FabricEngine> scene(const Options& o, bool collisions) {
  return o.scene == "tension" ? tension(o, collisions) : ply(o, collisions, collisions);
}

struct Result {
  double wall = 0, build = 0;
  long steps = 0;
  Index cps = 0;
  double phase[6] = {0, 0, 0, 0, 0, 0};  // refit, broad, narrow, respond, project, rest
  long rows = 0, sweeps = 0, unresolved = 0, unresolvedBand = 0, skipped = 0, renewed = 0, contacts = 0, crossings = 0, candidates = 0;
  Real residual = 0;
  Real vz = 0, maxOverlap = 0, balance = 0, work = 0;
  long broken = 0;
  std::uint64_t bits = 0;
#ifndef WOVEN_BASELINE
  CrossingCounts counts;
#else
  struct {
    long formed = 0, handedBack[5] = {}, moved = 0;
  } counts;
#endif
};

// The CPs the step's partial broad phase collided again (a baseline core does not count them).
long renewedOf(const CollisionStats& s) {
#ifndef WOVEN_BASELINE
  return s.renewed;
#else
  return 0 * s.steps;
#endif
}

std::uint64_t hashBits(std::uint64_t h, const void* p, std::size_t n) {
  const unsigned char* c = static_cast<const unsigned char*>(p);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  return h;
}

Result impact(const Options& o, int threads) {
  setThreads(threads);
  const auto b0 = std::chrono::steady_clock::now();
  auto e = scene(o, true);
  const bool cube = o.scene == "impact";
  if (cube) addCube(*e, o.V);
  const Real dt = o.safety * e->criticalDt();
  const long steps = o.steps > 0 ? o.steps : static_cast<long>(std::ceil(o.tEnd / dt - 1e-9));
  CollisionStage& st = *e->collisions();
  Result r;
  r.cps = e->fabric().nElems();
  for (int k = 0; k < o.warmup; ++k) e->step(dt);
  if (o.warmup > 0) st.stats = CollisionStats();  // the timed steps' figures only
  const auto t0 = std::chrono::steady_clock::now();
  r.build = std::chrono::duration<double>(t0 - b0).count();
  double lastWall = 0;
  for (long k = 0; k < steps; ++k) {
    e->step(dt);
    if (o.every > 0 && (k + 1) % o.every == 0) {
      const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("    step %5ld: %.2f ms/step, %ld contacts (%ld crossings), %ld rows, %ld unresolved, %ld candidates, "
                  "%ld renewed, cube vz %.2f, balance %.4g J\n", k + 1, 1e3 * (w - lastWall) / o.every, st.stats.contacts,
#ifndef WOVEN_BASELINE
                  st.stats.crossings.listed,
#else
                  0L,
#endif
                  st.stats.impulses.rows, st.stats.impulses.unresolved, st.stats.candidates, renewedOf(st.stats),
                  cube ? st.bodies[0].vel.z() : 0.0, e->dynamics().energy().balanceError());
#ifndef WOVEN_BASELINE
      // The census of the CP-pair contacts no crossing stands for: where the step's contact work goes
      // once crossings are handed back or yarns close up side by side (docs/collisions.md).
      const Fabric& f = e->fabric();
      long general = 0, side = 0, parallel = 0;
      for (const CPContact& c : st.contacts()) {
        if (c.crossing >= 0) continue;
        ++general;
        side += c.kind == ContactKind::Side;
        const Index a = f.elem0[c.cpA], b = f.elem0[c.cpB];
        const Vec3 da = f.pos[a + 1] - f.pos[a], db = f.pos[b + 1] - f.pos[b];
        parallel += std::abs(da.dot(db)) >= std::sqrt(0.5) * da.norm() * db.norm();  // within 45 degrees
      }
      std::printf("      %ld other contacts: %ld side by side, %ld between CPs within 45 degrees of parallel; %ld CPs broken\n",
                  general, side, parallel, static_cast<long>(std::count(f.alive.begin(), f.alive.end(), 0)));
#endif
      lastWall = w;
    }
    r.rows += st.stats.impulses.rows, r.sweeps += st.stats.impulses.iterations;
    r.unresolved += st.stats.impulses.unresolved, r.contacts += st.stats.contacts, r.candidates += st.stats.candidates;
    r.renewed += renewedOf(st.stats);
#ifndef WOVEN_BASELINE
    r.skipped += st.stats.impulses.skipped, r.unresolvedBand += st.stats.impulses.unresolvedBand;
    r.crossings += st.stats.crossings.listed;
#else
    r.unresolvedBand += st.stats.impulses.unresolved;
#endif
    r.residual = std::max(r.residual, st.stats.impulses.residual);
  }
  r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  releaseThreads();
  r.steps = steps;
  double inStage = 0;
  for (int k = 0; k < 5; ++k) r.phase[k] = st.stats.seconds[k], inStage += r.phase[k];
  r.phase[5] = r.wall - inStage;
  const Fabric& f = e->fabric();
  r.vz = cube ? st.bodies[0].vel.z() : 0.0;
  r.maxOverlap = st.stats.maxPenetration;
#ifndef WOVEN_BASELINE
  r.counts = st.stats.crossings;
#endif
  const EnergyBooks b = e->dynamics().energy();
  r.balance = b.balanceError(), r.work = b.work;
  r.broken = std::count(f.alive.begin(), f.alive.end(), 0);
  std::uint64_t h = 1469598103934665603ull;
  h = hashBits(h, f.pos.data(), f.pos.size() * sizeof(Vec3));
  h = hashBits(h, f.vel.data(), f.vel.size() * sizeof(Vec3));
  h = hashBits(h, f.secFlat.data(), f.secFlat.size() * sizeof(Real));
  h = hashBits(h, f.secDir.data(), f.secDir.size() * sizeof(Vec3));
  h = hashBits(h, f.alive.data(), f.alive.size());
  const Real books[6] = {b.kinetic, b.elastic, b.damped, b.work, b.contact, b.released};
  h = hashBits(h, books, sizeof books);
  for (const RigidBody& body : st.bodies) h = hashBits(h, &body.vel, sizeof(Vec3)), h = hashBits(h, &body.pos, sizeof(Vec3));
  r.bits = h;
  return r;
}

// CP-steps per second of the same scene's springs and integration alone (collisions and breakage off),
// the fastest of three runs of `steps` steps, on one thread.
double springsAlone(const Options& o, long steps) {
  setThreads(1);
  double best = 0;
  for (int k = 0; k < 3; ++k) {
    auto e = scene(o, false);
    const Real dt = o.safety * e->criticalDt();
    const auto t0 = std::chrono::steady_clock::now();
    for (long s = 0; s < steps; ++s) e->step(dt);
    const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::max(best, double(e->fabric().nElems()) * steps / w);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  const bool tensile = o.scene == "tension";
  const Index cps = o.baseline ? scene(o, false)->fabric().nElems() : 0;  // else the first run's count
  const double alone = o.baseline ? springsAlone(o, 300) : NAN;
  char spanBuf[64];
  std::snprintf(spanBuf, sizeof spanBuf, o.steps > 0 ? "%.0f steps" : "%.4g us", o.steps > 0 ? double(o.steps) : o.tEnd * 1e6);
  const std::string span = spanBuf;
  if (tensile)
    std::printf("bench_impact: scene tension, %d x %d yarns, %s steps after %d warm-up, sweeps %s, threads", o.yarns, o.yarns,
                o.steps > 0 ? std::to_string(o.steps).c_str() : "t_end's", o.warmup, o.sweepOrder.c_str());
  else
    std::printf("bench_impact: scene impact, side %.4g m, cp %d, cube %.0f m/s, %s, crossings %s, %d sweeps at most, sweeps %s, "
                "threads", o.side, o.cp, o.V, span.c_str(), o.crossings.c_str(), o.sweeps, o.sweepOrder.c_str());
  for (std::size_t q = 0; q < o.threads.size(); ++q) std::printf("%s%d", q ? "," : " ", o.threads[q]);
  std::printf(" (OMP_NUM_THREADS %s)\n", std::getenv("OMP_NUM_THREADS") ? std::getenv("OMP_NUM_THREADS") : "unset");
  if (o.baseline) std::printf("  springs + integration alone: %.3e CP-steps/s (fastest of 3, one thread)\n", alone);
  char head[512];
  std::snprintf(head, sizeof head, "{\"scene\": \"%s\", \"yarns\": %d, \"side\": %.6g, \"cp\": %d, \"steps_key\": %ld, \"warmup\": %d, "
                "\"sweep_order\": \"%s\", \"phase_names\": [\"refit\", \"broad\", \"narrow\", \"respond\", \"project\", \"rest\"], ",
                o.scene.c_str(), tensile ? o.yarns : 0, tensile ? 0.0 : o.side, tensile ? 4 : o.cp, o.steps, o.warmup,
                o.sweepOrder.c_str());
  std::string json = std::string(head) + "\"springs_alone_cp_steps_per_s\": " + (o.baseline ? std::to_string(alone) : "null") +
                     ", \"crossings\": \"" + o.crossings + "\", \"runs\": [";
  Index firstCps = cps;
  Result one;
  bool same = true;
  for (std::size_t q = 0; q < o.threads.size(); ++q) {
    const int n = o.threads[q];
    const Result r = impact(o, n);
    if (q == 0) {
      firstCps = r.cps;
      std::printf("  %d CPs, %ld timed steps%s\n", r.cps, r.steps, o.warmup ? (" after " + std::to_string(o.warmup) + " warm-up").c_str() : "");
    }
    const double rate = double(r.cps) * r.steps / r.wall;
    const double ideal1 = q > 0 ? idealLoopSeconds(1, 200) : 1, idealN = q > 0 ? idealLoopSeconds(n, 200) : 1;
    if (q == 0) one = r;
    same = same && r.bits == one.bits;
    std::printf("  %2d thread(s): %.3f s for %ld steps (built in %.2f s), %.3e CP-steps/s", n, r.wall, r.steps, r.build, rate);
    if (o.baseline) std::printf(", coupled / alone = %.4f (goal 0.0333)", rate / alone);
    if (q > 0) std::printf("; speed-up %.2fx (ideal loop %.2fx), bits %s", one.wall / r.wall, ideal1 / idealN,
                           r.bits == one.bits ? "the same" : "DIFFER");
    std::printf("\n    by phase [s]: refit %.3f broad %.3f narrow %.3f respond %.3f project %.3f rest %.3f\n", r.phase[0],
                r.phase[1], r.phase[2], r.phase[3], r.phase[4], r.phase[5]);
    std::printf("    per step: %.0f CPs out of their skin, %.0f candidates, %.0f contacts (%.0f crossings), %.0f rows, %.2f sweeps, %.2f %% of rows "
                "unresolved (%.2f %% beyond Eq. 4's 1e-6 m/s), largest miss %.3g m/s; %.0f row updates skipped\n",
                double(r.renewed) / r.steps, double(r.candidates) / r.steps, double(r.contacts) / r.steps,
                double(r.crossings) / r.steps, double(r.rows) / r.steps, double(r.sweeps) / r.steps,
                r.rows ? 100.0 * r.unresolved / r.rows : 0.0, r.rows ? 100.0 * r.unresolvedBand / r.rows : 0.0, r.residual, double(r.skipped) / r.steps);
    if (!tensile) std::printf("    cube vz %.4f m/s,", r.vz);
    std::printf("%slargest overlap %.3g um, energy balance %.3g %% of the work, %ld CPs broken\n", tensile ? "    " : " ",
                r.maxOverlap * 1e6, r.work != 0 ? 100 * r.balance / r.work : 0.0, r.broken);
    std::printf("    crossings: %ld formed, handed back %ld break, %ld separation, %ld turn, %ld slide, %ld kink; %ld moved\n",
                r.counts.formed, r.counts.handedBack[0], r.counts.handedBack[1], r.counts.handedBack[2],
                r.counts.handedBack[3], r.counts.handedBack[4], r.counts.moved);
    char buf[2048];
    std::snprintf(buf, sizeof buf,
                  "%s{\"threads\": %d, \"wall_s\": %.6g, \"build_s\": %.4g, \"steps\": %ld, \"cp_steps_per_s\": %.6g, \"ratio_to_alone\": %.6g, "
                  "\"speedup\": %.6g, \"ideal_speedup\": %.6g, \"bits\": \"%016llx\", \"same_bits\": %s, \"phase_s\": [%.4g, %.4g, %.4g, %.4g, %.4g, %.4g], "
                  "\"rows_per_step\": %.6g, \"sweeps_per_step\": %.4g, \"unresolved_pct\": %.4g, \"largest_miss\": %.4g, "
                  "\"vz\": %.10g, \"max_overlap\": %.6g, \"balance\": %.6g, \"work\": %.6g, \"broken\": %ld}",
                  q ? ", " : "", n, r.wall, r.build, r.steps, rate, o.baseline ? rate / alone : 0.0, one.wall / r.wall, ideal1 / idealN,
                  static_cast<unsigned long long>(r.bits), r.bits == one.bits ? "true" : "false", r.phase[0], r.phase[1], r.phase[2], r.phase[3], r.phase[4], r.phase[5],
                  double(r.rows) / r.steps, double(r.sweeps) / r.steps, r.rows ? 100.0 * r.unresolved / r.rows : 0.0,
                  r.residual, r.vz, r.maxOverlap, r.balance, r.work, r.broken);
    json += buf;
  }
  // What moving data between two threads costs here (core/ThreadCeiling.hpp), beside the ideal loop.
  std::string handoff = "null, \"remote_read_ratio\": null";
  if (*std::max_element(o.threads.begin(), o.threads.end()) > 1) {
    const CoreHandoff h = coreHandoff();
    if (std::isfinite(h.roundTripNs) && std::isfinite(h.remoteReadRatio)) {
      std::printf("  the cores: a cache line's round trip between two threads %.0f ns; 16 384 scattered lines the other thread "
                  "wrote read %.2fx as long as the reader's own\n", h.roundTripNs, h.remoteReadRatio);
      char b[128];
      std::snprintf(b, sizeof b, "%.6g, \"remote_read_ratio\": %.6g", h.roundTripNs, h.remoteReadRatio);
      handoff = b;
    }
  }
  json += "], \"cps\": " + std::to_string(firstCps) + std::string(", \"same_bits\": ") + (same ? "true" : "false") +
          ", \"handoff_round_trip_ns\": " + handoff + "}\n";
  if (!o.out.empty()) {
    FILE* fp = std::fopen(o.out.c_str(), "w");
    if (!fp) usage("out = " + o.out + " cannot be written");
    std::fputs(json.c_str(), fp);
    std::fclose(fp);
  }
  return same ? 0 : 1;
}
