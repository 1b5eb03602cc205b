// Threads change nothing (core/Parallel.hpp): the same scene stepped on 1, 2 and 3 threads ends in
// the same bits (positions, velocities, sections, broken elements, energy books, bodies). Scenes
// large enough that every parallel loop splits into several chunks: a decrimping weave with
// collisions, and a small clamped ply struck by a cube fast enough to break yarns.
#include "body_util.hpp"
#include "chain_util.hpp"
#include "core/Parallel.hpp"
#include "engine/FabricEngine.hpp"
#include "law/ImpulseLaw.hpp"
#include "law/RowBlocks.hpp"
#include "law/RowColouring.hpp"
#include "weave/WeaveBuilder.hpp"
#include "same_bits.hpp"
#include <gtest/gtest.h>
#include <algorithm>
#include <cstring>
#include <iterator>
#include <random>

using namespace woven;
using namespace woven_test;

namespace {

struct Outcome {
  Vec3Array pos, vel, dir;
  std::vector<Real> flat;
  std::vector<std::uint8_t> alive;
  EnergyBooks books;
  Vec3 bodyPos = Vec3::Zero(), bodyVel = Vec3::Zero();
  long contacts = 0, broken = 0;
  std::vector<CPContact> contactList;  // the last step's contacts, for the colouring test
  std::vector<BodyContact> bodyContactList;
  long impulseRows = 0, projected = 0;
};

void expectSame(const Outcome& a, const Outcome& b, int threads) {
  EXPECT_TRUE(sameBits(a.pos, b.pos)) << threads << " threads: positions";
  EXPECT_TRUE(sameBits(a.vel, b.vel)) << threads << " threads: velocities";
  EXPECT_TRUE(sameBits(a.flat, b.flat)) << threads << " threads: section flattening";
  EXPECT_TRUE(sameBits(a.dir, b.dir)) << threads << " threads: section directions";
  EXPECT_TRUE(sameBits(a.alive, b.alive)) << threads << " threads: broken elements";
  EXPECT_EQ(std::memcmp(&a.books, &b.books, sizeof(EnergyBooks)), 0) << threads << " threads: energy books";
  EXPECT_EQ(std::memcmp(a.bodyPos.data(), b.bodyPos.data(), sizeof(Vec3)), 0) << threads << " threads: body position";
  EXPECT_EQ(std::memcmp(a.bodyVel.data(), b.bodyVel.data(), sizeof(Vec3)), 0) << threads << " threads: body velocity";
  EXPECT_EQ(a.contacts, b.contacts);
  EXPECT_EQ(a.broken, b.broken);
}

Outcome finish(FabricEngine& e) {
  Outcome o;
  const Fabric& f = e.fabric();
  o.pos = f.pos, o.vel = f.vel, o.dir = f.secDir, o.flat = f.secFlat, o.alive = f.alive;
  o.books = e.dynamics().energy();
  o.contacts = e.collisions()->stats.contacts;
  o.contactList = e.collisions()->contacts(), o.bodyContactList = e.collisions()->bodyContacts();
  o.impulseRows = e.collisions()->stats.impulses.rows, o.projected = e.collisions()->stats.projection.pushed;
  o.broken = e.dynamics().breakage().brokenElements();
  if (!e.collisions()->bodies.empty()) o.bodyPos = e.collisions()->bodies[0].pos, o.bodyVel = e.collisions()->bodies[0].vel;
  return o;
}

// 24 x 24 yarns of KM2 706 (~4600 CPs: several chunks of nodes, CPs and pairs), sections settled,
// warp ends pulled at 5 m/s with collisions on (tree broad phase, cache, flattening, impulses,
// positional correction).
Outcome tension(int threads, int steps) {
  setThreads(threads);
  WeaveParams p = km2_706();
  p.nx = p.ny = 12;
  p.warpMaterial.dampingRatio = p.weftMaterial.dampingRatio = 0.1;
  FabricEngine e(buildWeave(p).fabric);
  ContactParams c;
  c.sweepOrder = SweepOrder::Coloured;  // the order whose sweeps run on the threads
  e.enableCollisions(c);
  e.collisions()->settle(e.fabric());
  for (const Yarn& y : e.fabric().yarns)
    if (y.family == YarnFamily::Warp) {
      e.dynamics().fix(y.firstNode);
      e.dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(5, 0, 0));
    }
  const Real dt = 0.7 * e.criticalDt();
  for (int s = 0; s < steps; ++s) e.step(dt);
  Outcome o = finish(e);
  setThreads(0);
  return o;
}

// The struck ply's runs in Debug and sanitizer builds (chain_util's runLength): a tenth of them, 30
// steps. The cube breaks its first yarns within 10 steps and every stage's loops run in each step: the
// sanitizers check the code paths, which the first steps take; the Release run keeps the 300 steps
// for the bits (these runs were 60 % of the sanitizer tier's time).
constexpr long kSlowSteps = 10;

// A 40 x 40-yarn ply (one CP per crossing, ~3200 CPs, every yarn end clamped, grid broad phase) and
// a 3 mm, 1 g cube touching its middle at 1000 m/s; breakage at 1 % raw strain; friction between
// yarns and with the cube.
WeaveParams struckPly() {
  WeaveParams p = km2_706();
  p.nx = p.ny = 20;
  p.cpPerSpan = 1;
  return p;
}

Outcome ballistic(int threads, int steps, BroadPhase broad = BroadPhase::Grid, Real skin = 1e-5,
                  SweepOrder order = SweepOrder::Coloured) {
  setThreads(threads);
  FabricEngine e(buildWeave(struckPly()).fabric);
  ContactParams c;
  c.positionCorrection = 0, c.flattenPasses = 1, c.maxIterations = 10, c.skin = skin;
  c.friction = 0.1, c.bodyFriction = 0.2;  // friction's energy share is summed per row, then in row order
  c.sweepOrder = order;  // an order whose sweeps run on the threads
  e.enableCollisions(c, broad);
  for (const Yarn& y : e.fabric().yarns) e.dynamics().fix(y.firstNode), e.dynamics().fix(y.firstNode + y.nNodes - 1);
  BreakageParams b;
  b.enabled = true, b.threshold = 0.01, b.filterLength = 0;
  e.dynamics().configureBreakage(b);
  e.collisions()->bodies.push_back(cubeAbove(e.fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -1000)));
  const Real dt = 0.7 * e.criticalDt();
  for (int s = 0; s < steps; ++s) e.step(dt);
  Outcome o = finish(e);
  setThreads(0);
  return o;
}


// The rows' nodes as ImpulseLaw lays them out for a contact list: the two nodes of each CP; the body
// rows after the yarn rows (-1: the serial tail).
struct RowNodes {
  const Fabric& f;
  const std::vector<CPContact>& cs;
  int operator()(Index r, Index* node) const {
    if (r >= static_cast<Index>(cs.size())) return -1;
    Real w[kMaxStencil];
    return contactStencil(f, cs[r], node, w);
  }
};

// A layout (RowColouring, RowBlocks) holds every row once, group by group up to lastGroup, each
// group's rows in row order, groupOf(r) the group row r is laid out in.
template <class Layout, class GroupOf>
void expectEveryRowOnceInRowOrder(const Layout& layout, int lastGroup, Index nRows, GroupOf&& groupOf) {
  std::vector<int> seen(static_cast<std::size_t>(nRows), 0);
  ASSERT_EQ(static_cast<Index>(layout.order().size()), nRows);
  for (int g = 0; g <= lastGroup; ++g)
    for (Index k = layout.begin(g); k < layout.begin(g + 1); ++k) {
      const Index r = layout.order()[k];
      ++seen[r];
      EXPECT_EQ(groupOf(r), g);
      if (k > layout.begin(g)) {
        EXPECT_LT(layout.order()[k - 1], r);
      }
    }
  for (Index r = 0; r < nRows; ++r) EXPECT_EQ(seen[r], 1) << "row " << r;
}
}  // namespace

TEST(Threads, TensionSceneIsTheSameBitsOnOneTwoAndThreeThreads) {
  const int steps = static_cast<int>(runLength(200, 8));
  const Outcome one = tension(1, steps);
  EXPECT_GT(one.contacts, 500);  // one per crossing (576) and the neighbours alongside: several chunks
  for (int t : {2, 3}) expectSame(one, tension(t, steps), t);
}

TEST(Threads, BallisticSceneWithBreakageIsTheSameBitsOnOneTwoAndThreeThreads) {
  const int steps = static_cast<int>(runLength(300, kSlowSteps));
  const Outcome one = ballistic(1, steps);
  EXPECT_GT(one.broken, 0) << "the cube breaks yarns within the run";
  EXPECT_GT(one.bodyVel.z(), -1000) << "the ply slows the cube";
  for (int t : {2, 3}) expectSame(one, ballistic(t, steps), t);
}

TEST(Threads, BlockedSweepsGiveTheSameBitsOnOneTwoAndThreeThreads) {
  const int steps = static_cast<int>(runLength(300, kSlowSteps));
  const Outcome one = ballistic(1, steps, BroadPhase::Grid, 1e-5, SweepOrder::Blocked);
  EXPECT_GT(one.broken, 0) << "the cube breaks yarns within the run";
  EXPECT_GT(one.bodyVel.z(), -1000) << "the ply slows the cube";
  for (int t : {2, 3}) expectSame(one, ballistic(t, steps, BroadPhase::Grid, 1e-5, SweepOrder::Blocked), t);
}

// The broad phase only lists candidates: the narrow phase decides each pair from its positions, so
// neither the skin (how long a list is kept) nor the collider (the grid re-colliding only the CPs
// that left their skin boxes, the OBB tree their yarns, sweep and prune all) may change a bit of the
// struck ply, breaks included: a pair the partial lists missed would show here. (That a listed pair
// no longer measured forgets its memory is tested in test_collisions.cpp: this run does not reach it.)
TEST(Threads, BallisticSceneIsTheSameBitsForAnySkinAndBroadPhase) {
  const int steps = static_cast<int>(runLength(300, kSlowSteps));
  const Outcome one = ballistic(1, steps);
  EXPECT_GT(one.broken, 0) << "the cube breaks yarns within the run";
  expectSame(one, ballistic(1, steps, BroadPhase::Grid, 4e-5), 1);
  expectSame(one, ballistic(1, steps, BroadPhase::SweepAndPrune, 1e-5), 1);
  expectSame(one, ballistic(1, steps, BroadPhase::YarnTree, 2e-5), 1);
}

// The impulse rows and the projection's contacts are swept colour by colour (law/RowColouring),
// each colour on the threads: the colouring of the struck ply's last contact set (the rows of the
// gap model: one per listed contact, then the body's) must be a colouring (no two rows of a colour
// share a node, every row once, the body rows in the serial tail), greedy (a row of colour c meets,
// for each lower colour, an earlier row of that colour at one of its nodes), and large enough that
// the same-bits test above splits colours over the threads.
TEST(Threads, RowsOfAColourShareNoNodeOnAStruckPly) {
  const Outcome o = ballistic(1, static_cast<int>(runLength(300, kSlowSteps)));
  const std::vector<CPContact>& cs = o.contactList;
  const Index nRows = static_cast<Index>(cs.size() + o.bodyContactList.size());
  const Index nNodes = static_cast<Index>(o.pos.size());
  ASSERT_GT(o.bodyContactList.size(), 0u) << "the cube touches the ply";
  ASSERT_GT(cs.size(), 1000u);
  const Fabric f = buildWeave(struckPly()).fabric;
  ASSERT_EQ(f.nNodes(), nNodes);
  const RowNodes rowNodes{f, cs};
  RowColouring col;
  col.build(nRows, nNodes, rowNodes);
  expectEveryRowOnceInRowOrder(col, RowColouring::kColours, nRows, [&](Index r) { return col.colour(r); });
  for (Index r = static_cast<Index>(cs.size()); r < nRows; ++r) EXPECT_EQ(col.colour(r), RowColouring::kColours);
  // No node twice in a colour; per node, its rows (in row order) with their colours.
  std::vector<std::vector<std::pair<Index, int>>> rowsAt(static_cast<std::size_t>(nNodes));
  Index largest = 0;
  for (int c = 0; c < col.colours(); ++c) {
    std::vector<std::uint8_t> used(static_cast<std::size_t>(nNodes), 0);
    largest = std::max(largest, col.begin(c + 1) - col.begin(c));
    for (Index k = col.begin(c); k < col.begin(c + 1); ++k) {
      Index node[kMaxStencil];
      const int n = rowNodes(col.order()[k], node);
      for (int q = 0; q < n; ++q) EXPECT_FALSE(used[node[q]]) << "colour " << c << ": node " << node[q] << " in two rows";
      for (int q = 0; q < n; ++q) used[node[q]] = 1;
    }
  }
  for (Index r = 0; r < static_cast<Index>(cs.size()); ++r) {
    Index node[kMaxStencil];
    const int n = rowNodes(r, node);
    for (int q = 0; q < n; ++q) rowsAt[node[q]].push_back({r, col.colour(r)});
  }
  long tail = 0;
  for (Index r = 0; r < static_cast<Index>(cs.size()); ++r) {
    const int c = col.colour(r);
    tail += c == RowColouring::kColours;
    Index node[kMaxStencil];
    const int n = rowNodes(r, node);
    for (int lower = 0; lower < std::min(c, RowColouring::kColours); ++lower) {
      bool met = false;
      for (int q = 0; q < n && !met; ++q)
        for (const auto& [other, oc] : rowsAt[node[q]]) met = met || (other < r && oc == lower);
      EXPECT_TRUE(met) << "row " << r << " of colour " << c << " could have taken colour " << lower;
    }
  }
  EXPECT_EQ(tail, 0) << "every yarn row found a colour";
  EXPECT_GT(largest, ImpulseLaw::kRowGrain) << "a colour large enough to be split over the threads";
  EXPECT_GE(col.colours(), 2);
  EXPECT_GT(o.impulseRows, 0);
}

// releaseThreads ends the calling thread's idle team between regions (OpenMP 5.0 pause), and refuses
// inside a region; a scene stepped after it (a new team) gives the bits of one stepped without.
TEST(Threads, ReleaseEndsTheIdleTeamOutsideARegionOnly) {
#ifdef _OPENMP
  std::vector<int> inside(2, -1);
#pragma omp parallel num_threads(2)
  inside[omp_get_thread_num()] = releaseThreads();
  EXPECT_EQ(inside[0], 0) << "refused inside a region";
  EXPECT_TRUE(releaseThreads());
  const int steps = static_cast<int>(runLength(60, 2));
  const Outcome kept = tension(2, steps);
  setThreads(2);
  ASSERT_TRUE(releaseThreads());
  const Outcome released = tension(2, steps);
  expectSame(kept, released, 2);
#else
  EXPECT_FALSE(releaseThreads());
#endif
}

// The collision stage's own count (ContactParams::threads >= 1) overrides woven's for its loops only
// while it runs, and 0 follows woven's.
TEST(Threads, ContactThreadsForceTheStageCountOnly) {
  setThreads(1);
  EXPECT_EQ(threads(), 1);
  {
    const ThreadCountScope scope(3);
    EXPECT_EQ(threads(), 3);
    const ThreadCountScope none(0);
    EXPECT_EQ(threads(), 3);
  }
  EXPECT_EQ(threads(), 1);
  setThreads(0);
  EXPECT_EQ(threads(), openmpThreads());
  ContactParams p;
  EXPECT_EQ(p.threads, 0);
  p.threads = -1;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "threads");
  p.threads = 65;
  EXPECT_EQ(parameterOf([&] { p.validate(); }), "threads");
}

// The blocks of the struck ply's last contact set (law/RowBlocks): every row once, each group's rows
// in row order, the body rows in the tail, no node in the rows of two groups of one phase (what lets
// a phase's groups run at once), every block a fair share of the rows and the serial seam small.
TEST(Threads, RowsOfTwoBlocksShareNoNodeOnAStruckPly) {
  const Outcome o = ballistic(1, static_cast<int>(runLength(300, kSlowSteps)), BroadPhase::Grid, 1e-5, SweepOrder::Blocked);
  const std::vector<CPContact>& cs = o.contactList;
  const Index nYarn = static_cast<Index>(cs.size()), nRows = nYarn + static_cast<Index>(o.bodyContactList.size());
  ASSERT_GT(o.bodyContactList.size(), 0u) << "the cube touches the ply";
  ASSERT_GT(nYarn, 1000);
  const Fabric f = buildWeave(struckPly()).fabric;
  const RowNodes rowNodes{f, cs};
  RowBlocks blocks;
  blocks.build(nRows, o.pos, rowNodes);
  expectEveryRowOnceInRowOrder(blocks, RowBlocks::kTail, nRows, [&](Index r) { return blocks.group(r); });
  for (Index r = nYarn; r < nRows; ++r) EXPECT_EQ(blocks.group(r), RowBlocks::kTail);
  for (Index r = 0; r < nYarn; ++r) EXPECT_NE(blocks.group(r), RowBlocks::kTail);
  for (int phase = 0; phase < RowBlocks::kPhases; ++phase) {
    std::vector<int> owner(o.pos.size(), -1);
    for (int g = RowBlocks::phaseBegin(phase); g < RowBlocks::phaseBegin(phase + 1); ++g)
      for (Index k = blocks.begin(g); k < blocks.begin(g + 1); ++k) {
        Index node[kMaxStencil];
        const int n = rowNodes(blocks.order()[k], node);
        for (Index i : std::vector<Index>(node, node + n)) {
          EXPECT_TRUE(owner[i] == -1 || owner[i] == g)
              << "phase " << phase << ": node " << i << " in groups " << owner[i] << " and " << g;
          owner[i] = g;
        }
      }
  }
  const Index cuts = blocks.begin(RowBlocks::kSeam) - blocks.begin(RowBlocks::kBlocks);
  const Index seam = blocks.begin(RowBlocks::kTail) - blocks.begin(RowBlocks::kSeam);
  EXPECT_GT(cuts, 0) << "rows across the cuts";
  EXPECT_LT(seam, nYarn / 50) << "rows across two cuts, solved on one thread";
  // Equal counts at the resolution of whole crossing columns (a persistent crossing's row is one per
  // crossing, all of a column's rows in one bin): no block under a quarter of the average.
  for (int b = 0; b < RowBlocks::kBlocks; ++b)
    EXPECT_GT(blocks.begin(b + 1) - blocks.begin(b), (nYarn - cuts) / (4 * RowBlocks::kBlocks)) << "block " << b;
}

// Blocked sweeps are Gauss-Seidel in another row order: swept to convergence, they reach the velocities
// the sequential order reaches (the rows' fixed point: the velocity change of least kinetic energy
// that meets every row, unique however many rows a node has) on the struck ply's last contacts. The
// same 100 steps in every build (the state decides how fast the sweeps converge); the velocities
// agree to about the tolerance times the rows a node has. Both orders skip, through their active
// sets, the rows nothing has changed since their last update: more than a quarter of the rows a
// sweep on average (the blocked order's set once held only its serial seam, under 2 % of the rows).
TEST(Threads, BlockedAndSequentialSweepsConvergeToTheSameVelocities) {
  const Outcome o = ballistic(1, 100, BroadPhase::Grid, 1e-5, SweepOrder::Blocked);
  const auto solved = [&](SweepOrder order, long& rows, long& unresolved, double& skippedPerSweep) {
    Fabric f = buildWeave(struckPly()).fabric;
    f.pos = o.pos, f.vel = o.vel, f.secFlat = o.flat, f.secDir = o.dir, f.alive = o.alive;
    for (Index i = 0; i < f.nNodes(); ++i) f.vel[i].z() -= 5.0 * (i % 7);  // rows that must push
    ContactParams p;
    p.sweepOrder = order, p.maxIterations = 20000, p.tolerance = 1e-7, p.solverTolerance = 0;
    ImpulseLaw law;
    ImpulseReport rep;
    law.resolve(f, o.contactList, [](const CPContact&) { return Real(0); }, 1e-8, p, rep);
    rows = rep.rows, unresolved = rep.unresolved;
    skippedPerSweep = rep.iterations > 0 ? double(rep.skipped) / rep.iterations : 0.0;
    return f.vel;
  };
  long rowsS = 0, rowsB = 0, missS = 0, missB = 0;
  double skipS = 0, skipB = 0;
  const Vec3Array vS = solved(SweepOrder::Sequential, rowsS, missS, skipS);
  const Vec3Array vB = solved(SweepOrder::Blocked, rowsB, missB, skipB);
  ASSERT_GT(rowsS, 1000);
  EXPECT_EQ(rowsB, rowsS);
  EXPECT_GT(skipS, 0.25 * rowsS) << "row updates skipped per sweep, sequential";
  EXPECT_GT(skipB, 0.25 * rowsB) << "row updates skipped per sweep, blocked";
  EXPECT_EQ(missS, 0);
  EXPECT_EQ(missB, 0);
  Real worst = 0, fastest = 0;
  for (std::size_t i = 0; i < vS.size(); ++i)
    worst = std::max(worst, (vS[i] - vB[i]).norm()), fastest = std::max(fastest, vS[i].norm());
  EXPECT_LT(worst, 1e-8 * fastest) << "largest difference " << worst << " m/s of " << fastest;
}

// The lists the broad phase joins and merges on the threads (core/Parallel.hpp) against the serial
// oracle, std::merge and concatenation: lists over several chunks, with equal elements across the
// two lists and at the chunks' edges, an empty list on either side, on 1, 2 and 3 threads.
TEST(Threads, ParallelMergeAndJoinGiveTheSerialLists) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> small(0, 3000);
  for (const auto& sizes : {std::pair<int, int>{20000, 7000}, {0, 5000}, {30000, 0}, {8192, 8193}}) {
    // Pairs keyed on a only (b tells the copies apart): std::merge's order of equal keys is tested.
    std::vector<std::pair<int, int>> a(sizes.first), b(sizes.second);
    for (auto& x : a) x = {small(rng), 0};
    for (auto& x : b) x = {small(rng), 1};
    const auto byKey = [](const std::pair<int, int>& x, const std::pair<int, int>& y) { return x.first < y.first; };
    std::stable_sort(a.begin(), a.end(), byKey), std::stable_sort(b.begin(), b.end(), byKey);
    std::vector<std::pair<int, int>> serial;
    std::merge(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(serial), byKey);
    std::vector<std::vector<int>> parts(7);
    std::vector<int> joined;
    for (auto& part : parts)
      for (int k = 0, m = small(rng) % 5 == 0 ? 0 : small(rng); k < m; ++k) part.push_back(k), joined.push_back(k);
    struct Key {  // the pair ordered by its key alone, as parallelMerge compares with <
      std::pair<int, int> v;
      bool operator<(const Key& o) const { return v.first < o.v.first; }
    };
    std::vector<Key> ka, kb;
    for (const auto& x : a) ka.push_back({x});
    for (const auto& x : b) kb.push_back({x});
    for (const int nThreads : {1, 2, 3}) {
      std::vector<Key> merged;
      parallelMerge(ka, kb, merged, nThreads);
      ASSERT_EQ(merged.size(), serial.size());
      for (std::size_t k = 0; k < serial.size(); ++k) ASSERT_EQ(merged[k].v, serial[k]) << nThreads << " threads, item " << k;
      std::vector<int> out;
      joinChunks(parts, out, nThreads);
      EXPECT_EQ(out, joined) << nThreads << " threads";
    }
  }
}
