// Collision handling: bound functor, colliders, flattening, impulses (conservation laws, Eq. 5),
// non-penetration, moving test against tunnelling, bad input, state files with sections.
#include "bound/CPBound.hpp"
#include "body_util.hpp"
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "geom/CPContact.hpp"
#include "geom/SegmentDistance.hpp"
#include "geom/SeparatingAxis.hpp"
#include "law/ImpulseLaw.hpp"
#include "weave/WeaveBuilder.hpp"
#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>

using namespace woven;
using namespace woven_test;

namespace {

// Flattening capacity of a locked contact.
Real locked(const CPContact&) { return 0.0; }

YarnSection roundSection(Real r) {
  YarnSection s;
  s.width = s.thickness = 2 * r;
  return s;
}

/// Yarn along direction (cos th, sin th, 0) through (0, 0, z) with n elements of length l0, centred.
Vec3Array line(Real th, Real z, int n, Real l0) {
  Vec3Array p;
  const Vec3 d(std::cos(th), std::sin(th), 0);
  for (int i = 0; i <= n; ++i) p.push_back(Vec3(0, 0, z) + (i - 0.5 * n) * l0 * d);
  return p;
}

/// Two single-CP yarns, parallel to x, A at z = 0, B at z = gap: the head-on pair of the impulse tests.
Fabric cpPair(Real gap, Real r = 1e-4, Real l0 = 1e-3) {
  Fabric f;
  f.addYarn(line(0, 0, 1, l0), km2Material(), roundSection(r));
  f.addYarn(line(0, gap, 1, l0), km2Material(), roundSection(r));
  return f;
}

/// A KM2 706 ply of n x n yarns with the default contact settings (the colliders' tests).
std::unique_ptr<FabricEngine> plyWithCollisions(int n) {
  WeaveParams p = km2_706();
  p.nx = p.ny = n;
  auto eng = std::make_unique<FabricEngine>(buildWeave(p).fabric);
  eng->enableCollisions(ContactParams());
  return eng;
}

/// The colliders' oracle: every pair i < j that `keep` selects and the gap model's filter keeps
/// (same-yarn pairs excluded over the widest flattened section, CandidatePairs.hpp) whose boxes
/// overlap, in order.
template <class Keep>
std::vector<CPPair> bruteForcePairs(const Fabric& f, const std::vector<OBB>& b, const PairFilter& filter, Keep keep) {
  std::vector<CPPair> out;
  for (Index i = 0; i < f.nElems(); ++i)
    for (Index j = i + 1; j < f.nElems(); ++j)
      if (keep(i, j) && !filter.excluded(f, i, j) && obbOverlap(b[i], b[j])) out.push_back({i, j});
  return out;
}

PairFilter gapModelFilter(const Fabric& f) {
  PairFilter filter;
  filter.configure(f, 1, semiAxes(1, ContactParams().mcd, ContactParams().rule).a);
  return filter;
}

Real kinetic(const Fabric& f) {
  Real k = 0;
  for (Index i = 0; i < f.nNodes(); ++i) k += 0.5 * f.mass[i] * f.vel[i].squaredNorm();
  return k;
}
Vec3 momentum(const Fabric& f) {
  Vec3 p = Vec3::Zero();
  for (Index i = 0; i < f.nNodes(); ++i) p += f.mass[i] * f.vel[i];
  return p;
}

}  // namespace

TEST(CPBound, EnclosesTheEllipticCylinderAndTouchesIt) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<Real> U(-1, 1), F(0, 0.6);
  for (SectionRule rule : {SectionRule::Paper, SectionRule::ConstantArea}) {
    Vec3Array pts{Vec3::Zero()};
    for (int i = 0; i < 8; ++i) pts.push_back(pts.back() + Vec3(1e-3, 0, 0) + 4e-4 * Vec3(U(rng), U(rng), U(rng)));
    Fabric f;
    f.addYarn(pts, km2Material(), roundSection(2e-4));
    for (Index k = 0; k < f.nNodes(); ++k) f.secFlat[k] = F(rng), f.secDir[k] = Vec3(U(rng), U(rng), U(rng));
    Vec3Array t;
    updateSectionFrames(f, t);
    const Real margin = 1e-6;
    for (Index e = 0; e < f.nElems(); ++e) {
      const OBB b = cpBound(f, t, e, rule, margin);
      Vec3 reach = Vec3::Zero();
      for (Index k : {f.elem0[e], f.elem0[e] + 1}) {
        EXPECT_NEAR(f.secDir[k].dot(t[k]), 0, 1e-12);
        const SemiAxes s = semiAxes(f.secRadius[k], f.secFlat[k], rule);
        const Vec3 u = t[k].cross(f.secDir[k]);
        for (int q = 0; q < 720; ++q) {
          const Real phi = q * M_PI / 360;
          const Vec3 p = f.pos[k] + s.a * std::cos(phi) * u + s.b * std::sin(phi) * f.secDir[k];
          EXPECT_LE(b.outside(p), -margin + 1e-15) << "rule " << int(rule) << " CP " << e;
          reach = reach.cwiseMax((b.axes.transpose() * (p - b.centre)).cwiseAbs());
        }
      }
      // Tight: each face is touched by the sampled ellipses to the sampling resolution (1 - cos(pi/720)).
      for (int ax = 0; ax < 3; ++ax) EXPECT_GT(reach[ax], (b.extent[ax] - margin) * (1 - 1e-5)) << ax;
    }
  }
}

TEST(Collider, TreeSweepAndPruneGridAndBruteForceGiveTheSamePairs) {
  const auto eng = plyWithCollisions(4);
  CollisionStage& cs = *eng->collisions();
  Fabric& f = eng->fabric();
  std::mt19937 rng(11);
  std::normal_distribution<Real> G(0, 1);
  long rebuiltFirst = 0;
  for (int trial = 0; trial < 4; ++trial) {
    if (trial > 0) {  // bend and shift the yarns, flatten random sections
      for (Vec3& x : f.pos) x += 1e-4 * trial * Vec3(G(rng), G(rng), G(rng));
      for (Real& e : f.secFlat) e = 0.3 * std::abs(G(rng)) > 0.6 ? 0.6 : 0.3 * std::abs(G(rng));
    }
    std::vector<CPPair> tree, sap, grid;
    cs.candidatePairs(f, BroadPhase::YarnTree, tree);
    if (trial == 0) rebuiltFirst = cs.tree.stats.rebuiltNodes;
    cs.candidatePairs(f, BroadPhase::SweepAndPrune, sap);
    cs.candidatePairs(f, BroadPhase::Grid, grid);
    // Brute force over all pairs with the same box test.
    const PairFilter filter = gapModelFilter(f);
    const std::vector<OBB>& b = cs.bounds();
    const std::vector<CPPair> brute = bruteForcePairs(f, b, filter, [](Index, Index) { return true; });
    ASSERT_GT(brute.size(), 100u) << "trial " << trial;
    EXPECT_EQ(tree, brute) << "trial " << trial;
    EXPECT_EQ(sap, brute) << "trial " << trial;
    EXPECT_EQ(grid, brute) << "trial " << trial;
    // The grid's hash table is split among the threads by slot ranges: the same pairs on any count.
    for (const int nThreads : {1, 2, 3}) {
      setThreads(nThreads);
      std::vector<CPPair> again;
      cs.candidatePairs(f, BroadPhase::Grid, again);
      EXPECT_EQ(again, brute) << "trial " << trial << ", " << nThreads << " threads";
    }
    setThreads(0);
    // The grid's partial phase (CollisionStage::broad: only the CPs out of their skin boxes look):
    // exactly the brute-force pairs with a flagged CP, a few flagged or most.
    for (const Real share : {0.05, 0.7}) {
      std::vector<std::uint8_t> dirty(f.nElems());
      std::bernoulli_distribution B(share);
      for (auto& d : dirty) d = B(rng);
      std::vector<CPPair> part, expect;
      GridCollider g;
      g.collide(f, b, filter, part, &dirty);
      for (const CPPair& q : brute)
        if (dirty[q.a] || dirty[q.b]) expect.push_back(q);
      ASSERT_GT(expect.size(), 5u) << "trial " << trial;
      EXPECT_EQ(part, expect) << "trial " << trial << " share " << share;
    }
  }
  EXPECT_GT(cs.tree.stats.rebuiltNodes, rebuiltFirst);  // the bent yarns degraded some nodes
}

// The grid kept between calls (CollisionStage::broad's partial phases): rounds of a few CPs whose
// boxes moved and grew, each call moving only those in the grid's cells, must list exactly the
// brute-force pairs of a moved CP on the boxes of that round. A 16 x 16 ply in cells of 0.3 mm fills
// more than 8 000 of them, so the cells' table grows (rehashes) five times while it is filled.
// Oracle: every pair's OBB test on the same boxes.
TEST(Collider, GridKeptBetweenCallsListsThePairsOfTheCPsThatMoved) {
  const auto eng = plyWithCollisions(16);
  CollisionStage& cs = *eng->collisions();
  const Fabric& f = eng->fabric();
  std::vector<CPPair> all;
  cs.candidatePairs(eng->fabric(), BroadPhase::Grid, all);  // the stage's refit: its bounds
  std::vector<OBB> b = cs.bounds();
  const PairFilter filter = gapModelFilter(f);
  GridCollider g;
  std::vector<CPPair> first;
  g.collide(f, b, filter, first);
  ASSERT_EQ(g.rebuilds, 1);
  std::mt19937 rng(5);
  std::normal_distribution<Real> G(0, 1);
  std::bernoulli_distribution B(0.1);
  for (int round = 0; round < 6; ++round) {
    std::vector<std::uint8_t> moved(f.nElems(), 0);
    for (Index e = 0; e < f.nElems(); ++e)
      if (B(rng)) {  // moved ~25 um (cells of 0.3 mm), grown by as much: it still holds its CP's axis
        moved[e] = 1;
        const Vec3 d = 1.5e-5 * Vec3(G(rng), G(rng), G(rng));
        b[e].centre += d;
        b[e].extent.array() += d.norm();
      }
    std::vector<CPPair> part;
    g.collide(f, b, filter, part, &moved);
    const std::vector<CPPair> expect = bruteForcePairs(f, b, filter, [&](Index i, Index j) { return moved[i] || moved[j]; });
    ASSERT_GT(expect.size(), 100u) << "round " << round;
    EXPECT_EQ(part, expect) << "round " << round;
  }
  EXPECT_EQ(g.rebuilds, 1);  // every later call moved its CPs in the kept grid
  // A CP breaks and its box flies 40 cells away (a broken piece's skin box): it leaves the grid
  // without a rebuild, however many cells its box spans now (a partial call whose flagged box spans
  // more than kMaxSpan cells rebuilds the grid, and a broken piece's did so at 812 of the default
  // impact's 1 489 partial calls), and the pairs are still the brute-force ones.
  Fabric& broken = eng->fabric();
  const Index gone = f.nElems() / 2;
  broken.alive[gone] = 0;
  b[gone].centre += Vec3(40 * g.cellSize, 0, 0);
  b[gone].extent.array() += (GridCollider::kMaxSpan + 2) * g.cellSize;
  std::vector<std::uint8_t> moved(f.nElems(), 0);
  moved[gone] = moved[gone + 1] = 1;
  b[gone + 1].centre += Vec3(1e-5, 0, 0);
  std::vector<CPPair> part;
  g.collide(f, b, filter, part, &moved);
  const std::vector<CPPair> expect = bruteForcePairs(f, b, filter, [&](Index i, Index j) { return moved[i] || moved[j]; });
  ASSERT_GE(expect.size(), 2u);
  EXPECT_EQ(part, expect);
  for (const CPPair& q : part) EXPECT_TRUE(q.a != gone && q.b != gone);
  EXPECT_EQ(g.rebuilds, 1);
}

// A pair the broad phase keeps listing (a skin of 2 mm) while the narrow phase stops measuring it
// (its axes 1 mm apart) must come back as a new pair: here it comes back from the other side, and
// the remembered normal of the first contact would read that as the axes passed through each other
// (an overlap of twice the yarn's thickness). Oracle: the crossing's gap from its axes' distance,
// and the same stage started afresh on the last positions.
TEST(CollisionStage, APairNoLongerMeasuredForgetsItsMemoryWhileStillListed) {
  const Real r = 1e-4, l0 = 1e-3, gap = 1e-6, z = 2 * r + gap;
  const auto run = [&](const std::vector<Real>& heights) {
    Fabric f;
    f.addYarn(line(0, 0, 1, l0), km2Material(), roundSection(r));
    f.addYarn(line(M_PI / 2, heights[0], 1, l0), km2Material(), roundSection(r));
    FabricEngine e(std::move(f));
    ContactParams c;
    c.skin = 2e-3;
    c.crossings = Crossings::Chords;  // the general pipeline's memory (a persistent crossing keeps its side)
    e.enableCollisions(c, BroadPhase::Grid);
    for (Index k = 0; k < 4; ++k) e.dynamics().fix(k);
    std::vector<Real> gaps;
    for (Real h : heights) {
      for (Index k : {2, 3}) e.fabric().pos[k].z() = h;
      e.step(1e-8);
      gaps.push_back(e.collisions()->contacts().empty() ? INFINITY : e.collisions()->contacts()[0].gap);
      EXPECT_EQ(e.collisions()->stats.broadPhases, 1) << "the pair stays listed";
    }
    return gaps;
  };
  const std::vector<Real> listed = run({z, z + 1e-3, -z}), fresh = run({-z});
  EXPECT_NEAR(listed[0], gap, 1e-12);
  EXPECT_EQ(listed[1], INFINITY) << "not measured 1 mm apart";
  EXPECT_NEAR(listed[2], gap, 1e-12) << "came back from below: a new pair";
  EXPECT_EQ(listed[2], fresh[0]);
}

TEST(ImpulseLaw, EachImpulseConservesMomentum) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> U(-1, 1), S(0, 1);
  ContactParams p;
  ImpulseLaw law;
  for (int trial = 0; trial < 2000; ++trial) {
    Fabric f = cpPair(1e-4 * (1 + S(rng)));
    for (Vec3& v : f.vel) v = 100 * Vec3(U(rng), U(rng), U(rng));
    p.restitution = S(rng), p.friction = trial % 2 ? 0.0 : 2 * S(rng);
    CPContact c;
    c.cpA = 0, c.cpB = 1, c.gap = 0, c.sA = S(rng), c.sB = S(rng);
    c.normal = Vec3(U(rng), U(rng), U(rng)).normalized();
    const Vec3 p0 = momentum(f);
    Real scale = 0;
    for (Index i = 0; i < f.nNodes(); ++i) scale += f.mass[i] * f.vel[i].norm();
    ImpulseReport rep;
    law.resolve(f, {c}, locked, 1e-8, p, rep);
    EXPECT_LE((momentum(f) - p0).norm(), 1e-12 * scale);
    const Real dE = rep.energyChange + law.restitute(f, p);
    EXPECT_LE((momentum(f) - p0).norm(), 1e-12 * scale);
    if (rep.rows) {
      EXPECT_LE(dE, 1e-12 * kinetic(f));  // e <= 1 and friction never add energy
    }
  }
}

TEST(ImpulseLaw, HeadOnPairElasticKeepsEnergyPlasticEndsTogether) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<Real> S(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    for (Real e : {0.0, 1.0}) {
      Fabric f = cpPair(2e-4);
      const Real vA = 50 + 100 * S(rng), vB = -(10 + 100 * S(rng));  // approaching along z
      f.vel[0] = f.vel[1] = Vec3(0, 0, vA);
      f.vel[2] = f.vel[3] = Vec3(0, 0, vB);
      f.vel[1].z() += 20 * S(rng);  // and a spin of A
      ContactParams p;
      p.restitution = e;
      CPContact c;
      c.cpA = 0, c.cpB = 1, c.gap = 0, c.normal = Vec3::UnitZ(), c.sA = S(rng), c.sB = S(rng);
      const Real ke0 = kinetic(f);
      auto vn = [&] {
        return ((1 - c.sB) * f.vel[2] + c.sB * f.vel[3] - (1 - c.sA) * f.vel[0] - c.sA * f.vel[1]).dot(c.normal);
      };
      const Real vn0 = vn();
      ImpulseLaw law;
      ImpulseReport rep;
      law.resolve(f, {c}, locked, 1e-8, p, rep);  // pass 1: stop the approach
      law.restitute(f, p);                         // pass 2: give back e of it (Eq. 5 in total)
      ASSERT_EQ(rep.rows, 1);
      EXPECT_EQ(rep.unresolved, 0);
      if (e == 1) {
        EXPECT_NEAR(kinetic(f), ke0, 1e-9 * ke0);
        EXPECT_NEAR(vn(), -vn0, 1e-9 * std::abs(vn0));
      } else {
        EXPECT_NEAR(vn(), 0, 1e-12 * std::abs(vn0));  // the contact points move together along n
        EXPECT_LT(kinetic(f), ke0);
      }
    }
  }
}

// Coulomb friction on one contact: the tangential impulse is bounded by mu times the normal one, so a
// sliding pair loses mu |dvn| of tangential relative speed (both directions see the same effective
// mass), and a pair with a large mu sticks (tangential relative velocity 0).
TEST(ImpulseLaw, CoulombFrictionSlidesWithinTheConeAndSticksBeyond) {
  for (Real mu : {0.1, 0.3, 10.0}) {
    Fabric f = cpPair(2e-4);
    f.vel[0] = f.vel[1] = Vec3(3, 0, 10);    // A sliding along x while approaching B
    f.vel[2] = f.vel[3] = Vec3(0, 0, -10);
    ContactParams p;
    p.friction = mu;
    CPContact c;
    c.cpA = 0, c.cpB = 1, c.gap = 0, c.normal = Vec3::UnitZ(), c.sA = c.sB = 0.5;
    auto rel = [&] { return Vec3(0.5 * (f.vel[2] + f.vel[3] - f.vel[0] - f.vel[1])); };
    const Vec3 v0 = rel();
    ImpulseLaw law;
    ImpulseReport rep;
    law.resolve(f, {c}, locked, 1e-8, p, rep);
    const Vec3 v1 = rel();
    EXPECT_NEAR(v1.z(), 0, 1e-9);                   // normal approach stopped (e = 0)
    const Real dvn = std::abs(v1.z() - v0.z()), slip0 = std::abs(v0.x()), slip1 = std::abs(v1.x());
    if (mu * dvn < slip0) {
      EXPECT_NEAR(slip0 - slip1, mu * dvn, 1e-9 * dvn) << "mu " << mu;  // sliding: |dJt| = mu |Jn|
    } else {
      EXPECT_NEAR(slip1, 0, 1e-9) << "mu " << mu;                       // sticking
    }
    EXPECT_LT(rep.energyChange, 0);
  }
}

TEST(Flattening, CrossingRoundYarnsFlattenToTheGapAndLockAtTheMCD) {
  const Real r0 = 1e-4, l0 = 2e-4;
  for (SectionRule rule : {SectionRule::ConstantArea, SectionRule::Paper}) {
    for (Real g0 : {1.2e-4, 0.6e-4}) {  // centre gap: needs eps = 0.4 (free) or 0.7 (> MCD 0.6: locked)
      Fabric f;
      f.addYarn(line(0, 0, 4, l0), km2Material(), roundSection(r0));
      f.addYarn(line(M_PI / 2, g0, 4, l0), km2Material(), roundSection(r0));
      ContactParams p;
      p.rule = rule;
      CollisionStage cs(p);
      const Real left = cs.settle(f);
      const Index midA = 2, midB = 5 + 2;  // the crossing nodes
      const Real epsNeed = 1 - 0.5 * g0 / r0;
      for (Index k : {midA, midB}) {
        const SemiAxes s = semiAxes(f.secRadius[k], f.secFlat[k], rule);
        if (epsNeed < p.mcd) {
          EXPECT_NEAR(s.b, 0.5 * g0, 1e-9 * r0) << "rule " << int(rule);
        } else {
          EXPECT_EQ(f.secFlat[k], p.mcd);
        }
        EXPECT_NEAR(std::abs(f.secDir[k].z()), 1, 1e-12);  // flattened along the contact normal
        if (rule == SectionRule::ConstantArea) EXPECT_NEAR(s.a * s.b, r0 * r0, 1e-12 * r0 * r0);
        else EXPECT_NEAR(s.a, r0 * (1 + f.secFlat[k]), 1e-15);
        EXPECT_LE(f.secFlat[k], p.mcd);
      }
      if (epsNeed < p.mcd) EXPECT_LE(left, 1e-9 * r0);
      else EXPECT_NEAR(left, 2 * r0 * (1 - p.mcd) - g0, 1e-9 * r0);  // what the MCD leaves to the impulses
    }
  }
}

// A projectile pressing round sections flattens them as a yarn does (paper Sec. 5.1 steps 1-3 for
// any two colliding OBBs; model Gap): a ball resting over a node, a cube's face over a whole yarn,
// each overlapping the round sections by r0 eps, nothing moving. Closed form: the pressed nodes
// flatten to eps (b = r0 (1 - eps) meets the body), or lock at the MCD and leave r0 (eps - MCD) to
// the impulses. The paper's model keeps its own response: its body contacts flatten nothing.
TEST(Flattening, AProjectilePressingRoundSectionsFlattensThemToItsSurface) {
  const Real r0 = 1e-4, l0 = 2e-4;
  for (ContactModel model : {ContactModel::Gap, ContactModel::Paper})
    for (int shape : {0, 1})          // ball over node 2, cube over the yarn
      for (Real eps : {0.4, 0.7}) {   // free, or past the MCD 0.6
        Fabric f;
        f.addYarn(line(0, 0, 4, l0), km2Material(), roundSection(r0));
        FabricEngine e(std::move(f));
        ContactParams p;
        p.model = model;
        e.enableCollisions(p, BroadPhase::Grid);
        for (Index k = 0; k < 5; ++k) e.dynamics().fix(k);
        // The body's lowest point r0 (1 - eps) above the axis; the ball (radius r0) clears nodes 1
        // and 3, the cube's face (2 mm wide) covers the yarn.
        const Real top = r0 * (1 - eps), R = shape == 0 ? r0 : 1e-3;
        e.collisions()->bodies.push_back(shape == 0 ? ball(R, 0, Vec3(0, 0, top + R), Vec3::Zero())
                                                    : cube(R, 0, Vec3(0, 0, top + R), Vec3::Zero()));
        e.step(1e-9);
        const CollisionStats& st = e.collisions()->stats;
        const Fabric& g = e.fabric();
        const std::string what = std::string(shape == 0 ? "ball" : "cube") + " eps " + std::to_string(eps) +
                                 (model == ContactModel::Gap ? " gap" : " paper");
        if (model == ContactModel::Paper) {
          for (Index k = 0; k < 5; ++k) EXPECT_EQ(g.secFlat[k], 0) << what;
          continue;
        }
        for (Index k = 0; k < 5; ++k) {
          // The ball's two contacts measure at node 2, as the ends of CPs 1 and 2; each CP's nodes
          // give the same share of what they have left (flattenAt, as for yarn pairs): nodes 1-3.
          if (shape == 0 && (k == 0 || k == 4)) {
            EXPECT_EQ(g.secFlat[k], 0) << what << " node " << k;
            continue;
          }
          EXPECT_NEAR(g.secFlat[k], std::min(eps, p.mcd), 1e-9) << what << " node " << k;
          EXPECT_NEAR(std::abs(g.secDir[k].z()), 1, 1e-12) << what << " node " << k;  // along the normal
        }
        EXPECT_NEAR(st.bodyPenetration, r0 * std::max(Real(0), eps - p.mcd), 1e-9 * r0) << what;
      }
}

TEST(CollisionParams, BadInputNamesTheParameter) {
  auto bad = [](auto edit) {
    ContactParams p;
    edit(p);
    return parameterOf([&] { p.validate(); });
  };
  EXPECT_EQ(bad([](ContactParams& p) { p.mcd = 0; }), "mcd");
  EXPECT_EQ(bad([](ContactParams& p) { p.mcd = 1; }), "mcd");
  EXPECT_EQ(bad([](ContactParams& p) { p.mcd = NAN; }), "mcd");
  EXPECT_EQ(bad([](ContactParams& p) { p.restitution = -0.01; }), "restitution");
  EXPECT_EQ(bad([](ContactParams& p) { p.restitution = 1.01; }), "restitution");
  EXPECT_EQ(bad([](ContactParams& p) { p.friction = -1e-3; }), "friction");
  EXPECT_EQ(bad([](ContactParams& p) { p.margin = -1e-9; }), "margin");
  EXPECT_EQ(bad([](ContactParams& p) { p.tolerance = 0; }), "tolerance");
  EXPECT_EQ(bad([](ContactParams&) {}), "");
  FabricEngine eng(cpPair(1e-3));
  ContactParams p;
  p.mcd = 1.5;
  EXPECT_EQ(parameterOf([&] { eng.enableCollisions(p); }), "mcd");
  EXPECT_EQ(eng.collisions(), nullptr);  // nothing changed
  EXPECT_EQ(parameterOf([&] { sectionRuleByName("oval"); }), "section_rule");
}

// A thin CP shot across a yarn at 1000 m/s with dt at the stable limit moves 25x its own thickness
// per step, so only the moving test can stop it. Against a fixed yarn: e = 1 sends it back at
// 1000 m/s, e = 0 stops it in touch; against a yarn clamped at its ends (200 m/s) it never passes
// through.
TEST(MovingContact, NoTunnellingAt1000MetresPerSecond) {
  const Real r0 = 5e-6, l0 = 2e-3;  // 10 um thick yarns, 2 mm CPs: dt_crit ~ 2.5e-7 s, 250 um per step
  for (bool fixedTarget : {true, false}) {
    for (Real e : {0.0, 1.0}) {
      for (Real offset : {0.0, 0.37, 0.5, 0.9}) {  // where along A's CP (0.5: on a node) the shot lands
        Fabric f;
        f.addYarn(line(0, 0, 6, l0), km2Material(), roundSection(r0));
        Vec3Array pts = line(M_PI / 2, 2.3e-3, 1, l0);
        for (Vec3& x : pts) x.x() += (offset - 0.5) * l0;
        f.addYarn(pts, km2Material(), roundSection(r0));
        // Against the clamped yarn at 200 m/s (the ballistic speed): at 1000 m/s it would stretch
        // past any failure strain before stopping the shot.
        const Real speed = fixedTarget ? 1000 : 200;
        f.vel[7] = f.vel[8] = Vec3(0, 0, -speed);
        FabricEngine eng(std::move(f));
        for (Index i = 0; i <= 6; ++i)
          if (fixedTarget || i == 0 || i == 6) eng.dynamics().fix(i);
        ContactParams p;
        p.restitution = e;
        p.projectionSlop = 1e-9;  // an absolute length: this yarn is 10 um thick
        eng.enableCollisions(p);
        const Real dt = eng.criticalDt();
        Real minGap = INFINITY;
        for (int s = 0; s < 60; ++s) {
          eng.step(dt);
          const Fabric& g = eng.fabric();
          const Vec3 b = 0.5 * (g.pos[7] + g.pos[8]);  // B's centre over A's centre line below it
          const Index k = std::min<Index>(5, static_cast<Index>(std::floor(b.x() / l0 + 3)));
          const Real t = (b.x() - g.pos[k].x()) / (g.pos[k + 1].x() - g.pos[k].x());
          minGap = std::min(minGap, b.z() - ((1 - t) * g.pos[k].z() + t * g.pos[k + 1].z()));
        }
        const std::string what = "fixed " + std::to_string(fixedTarget) + " e " + std::to_string(e) + " offset " +
                                 std::to_string(offset);
        EXPECT_GT(minGap, 0) << what;
        const CollisionStats& st = eng.collisions()->stats;
        EXPECT_GT(st.steps, 0);
        if (fixedTarget) {
          EXPECT_LT(st.maxPenetration, 0.01 * 2 * r0) << what;
          EXPECT_GT(minGap, 2 * r0 * (1 - p.mcd) - 0.01 * 2 * r0) << what;  // no deeper than the locked sections
          const Real vz = 0.5 * (eng.fabric().vel[7].z() + eng.fabric().vel[8].z());
          EXPECT_NEAR(vz, e * speed, 1e-6 * speed) << what;  // Eq. 5 through the weights, B's spin aside
        }
      }
    }
  }
}

// Yarns dropped (free, 1-10 m/s) or pressed (ends driven down, then held) onto a closed layer of
// clamped yarns, at random angles (30-150 degrees to the layer), offsets and restitutions. Transient
// overlaps appear where flattened sections widen into their neighbours or a CP turns end-on (yarns
// have no bending stiffness); the positional correction removes them. In the state each run hands
// over, the largest overlap stays under 1 % of the yarn thickness.
TEST(NonPenetration, RandomDropsAndPressesOntoALayer) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<Real> U(-1, 1), S(0, 1);
  const Real r0 = 1e-4, l0 = 2e-4;
  const int seeds = kSlowBuild ? 2 : 6;
  for (int seed = 0; seed < seeds; ++seed) {
    for (bool press : {false, true}) {
      Fabric f;
      for (int k = 0; k < 3; ++k) {
        Vec3Array pts = line(0, 0, 12, l0);
        for (Vec3& x : pts) x.y() += (k - 1) * 3 * r0;  // a closed layer: at the MCD, 2a = 3 r0
        f.addYarn(pts, km2Material(0.3), roundSection(r0));
      }
      const Index firstDropped = f.nNodes();
      for (int k = 0; k < 2; ++k) {
        Vec3Array pts = line(M_PI * (1 + 4 * S(rng)) / 6, 2.2 * r0 + 2.2 * r0 * k, 10, l0);  // 30-150 deg to the layer
        const Vec3 shift = Vec3(U(rng), U(rng), 0) * 3e-4;
        for (Vec3& x : pts) x += shift;
        f.addYarn(pts, km2Material(0.3), roundSection(r0));
      }
      const Real speed = 1 + 9 * S(rng);
      for (Index i = firstDropped; i < f.nNodes(); ++i) f.vel[i] = Vec3(0, 0, -speed);
      FabricEngine eng(std::move(f));
      const Fabric& g = eng.fabric();
      for (Index y = 0; y < 3; ++y) eng.dynamics().fix(g.yarns[y].firstNode), eng.dynamics().fix(g.yarns[y].firstNode + 12);
      std::vector<Index> pressed;
      if (press)
        for (Index y = 3; y < 5; ++y) pressed.push_back(g.yarns[y].firstNode), pressed.push_back(g.yarns[y].firstNode + 10);
      for (Index i : pressed) eng.dynamics().prescribeVelocity(i, Vec3(0, 0, -speed));
      ContactParams p;
      p.mcd = 0.5;
      p.restitution = 0.3 * S(rng);
      p.rule = SectionRule::Paper;
      eng.enableCollisions(p);
      const Real dt = 0.7 * eng.criticalDt();
      const int travel = static_cast<int>(std::ceil(2 * r0 / speed / dt));  // down to the layer and into it
      for (int s = 0; s < travel; ++s) eng.step(dt);
      for (Index i : pressed) eng.dynamics().fix(i);  // hold the press
      for (int s = 0; s < 1000; ++s) eng.step(dt);
      const CollisionStats& st = eng.collisions()->stats;
      const std::string what = "seed " + std::to_string(seed) + (press ? " pressed" : " dropped");
      const Real left = eng.collisions()->overlap(eng.fabric());  // in the state the run hands over
      EXPECT_LT(left, 0.01 * 2 * r0) << what << ", largest transient " << st.maxPenetration;
      EXPECT_EQ(st.impulses.unresolved, 0) << what;
      Real maxFlat = 0;  // the yarns met: sections flattened somewhere
      for (Real e : g.secFlat) maxFlat = std::max(maxFlat, e);
      EXPECT_GT(maxFlat, 0) << what;
      EXPECT_GT(st.contacts, 0) << what;
    }
  }
}

// Both contact models: the paper's carried contacts and the gap model's pair memory (side-by-side
// kind, normal side) travel in the state file (tests/cpp/test_checkpoint.cpp: against the straight run).
TEST(StateIO, SectionsAndClockRoundTripAndTheRunContinuesBitForBit) {
 for (ContactModel model : {ContactModel::Paper, ContactModel::Gap}) {
  WeaveParams p = km2_706();
  p.nx = p.ny = 2;
  ContactParams cp;
  cp.model = model;
  cp.cacheDistance = 1e-6;  // carried contacts on both sides: they must not tell the runs apart
  auto fresh = [&] {
    auto e = std::make_unique<FabricEngine>(buildWeave(p).fabric);
    e->enableCollisions(cp);
    e->collisions()->settle(e->fabric());
    for (const Yarn& y : e->fabric().yarns)
      if (y.family == YarnFamily::Warp) e->dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(2, 0, 0));
    return e;
  };
  auto a = fresh();
  const Real dt = 0.7 * a->criticalDt();
  for (int s = 0; s < 40; ++s) a->step(dt);
  const std::string path = ::testing::TempDir() + "/woven_sections.state";
  a->saveState(path);
  long cached = 0;
  for (int s = 0; s < 40; ++s) a->step(dt), cached += a->collisions()->stats.cached;
  if (model == ContactModel::Paper) {
    EXPECT_GT(cached, 0);  // the gap model carries no contacts
  }

  auto b = fresh();
  b->setState(loadState(path, b->fabric().nNodes()));
  EXPECT_EQ(b->dynamics().stepCount(), 40);
  for (int s = 0; s < 40; ++s) b->step(dt);
  const Fabric &fa = a->fabric(), &fb = b->fabric();
  EXPECT_EQ(std::memcmp(fa.pos.data(), fb.pos.data(), fa.pos.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(std::memcmp(fa.vel.data(), fb.vel.data(), fa.vel.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(std::memcmp(fa.secFlat.data(), fb.secFlat.data(), fa.secFlat.size() * sizeof(Real)), 0);
  EXPECT_EQ(std::memcmp(fa.secDir.data(), fb.secDir.data(), fa.secDir.size() * sizeof(Vec3)), 0);
  Real maxFlat = 0;
  for (Real e : fa.secFlat) maxFlat = std::max(maxFlat, e);
  EXPECT_GT(maxFlat, 0.3);  // the sections were part of the state
  std::remove(path.c_str());
 }
}

// The Verlet skin only decides how often the broad phase runs: the contacts, and so the whole run,
// are the same bit for bit as with a broad phase every step.
TEST(Collider, SkinChangesNothingButHowOftenTheBroadPhaseRuns) {
  WeaveParams p = km2_706();
  p.nx = p.ny = 2;
  Vec3Array pos[2];
  long broadPhases[2];
  for (int k = 0; k < 2; ++k) {
    FabricEngine e(buildWeave(p).fabric);
    ContactParams c;
    c.skin = k == 0 ? 0.0 : 20e-6;
    e.enableCollisions(c);
    e.collisions()->settle(e.fabric());
    for (const Yarn& y : e.fabric().yarns)
      if (y.family == YarnFamily::Warp) e.dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(5, 0, 0));
    const Real dt = 0.7 * e.criticalDt();
    for (int s = 0; s < 400; ++s) e.step(dt);
    pos[k] = e.fabric().pos;
    broadPhases[k] = e.collisions()->stats.broadPhases;
  }
  EXPECT_EQ(std::memcmp(pos[0].data(), pos[1].data(), pos[0].size() * sizeof(Vec3)), 0);
  EXPECT_GE(broadPhases[0], 400);  // every step (and the settling passes)
  EXPECT_LT(broadPhases[1], 100);
}

// The narrow phase on two threads finds the same contacts in the same order: the run is the same
// bit for bit as on one.
TEST(Collider, NarrowPhaseThreadsChangeNothing) {
  WeaveParams p = km2_706();
  p.nx = p.ny = 9;  // > 4096 candidate pairs, so the second thread works
  Vec3Array pos[2];
  for (int k = 0; k < 2; ++k) {
    FabricEngine e(buildWeave(p).fabric);
    ContactParams c;
    c.threads = k + 1;
    c.crossings = Crossings::Chords;  // every CP pair in the general narrow phase (persistent: tests/cpp/test_crossings.cpp)
    e.enableCollisions(c);
    e.collisions()->settle(e.fabric());
    for (const Yarn& y : e.fabric().yarns)
      if (y.family == YarnFamily::Warp) e.dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(5, 0, 0));
    const Real dt = 0.7 * e.criticalDt();
    for (int s = 0; s < runLength(60, 3); ++s) e.step(dt);
    ASSERT_GT(e.collisions()->candidates().size(), 4096u);
    pos[k] = e.fabric().pos;
  }
  EXPECT_EQ(std::memcmp(pos[0].data(), pos[1].data(), pos[0].size() * sizeof(Vec3)), 0);
}

// The contact cache carries a pair's contact while its four nodes move together: over 400 steps of
// decrimping at 2 m/s, a run with the default cache (0.1 um) stays within 1 % of the yarn thickness
// of the run that tests every pair every step (measured 0.8 um; 2.2e-7 m with 0.01 um, 3.1 um with
// 1 um: the runs part in proportion to the cache distance, and any perturbation grows somewhat).
TEST(Collider, ContactCacheFollowsTheUncachedRun) {
  WeaveParams p = km2_706();
  p.nx = p.ny = 2;
  Vec3Array pos[2];
  long cached[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    FabricEngine e(buildWeave(p).fabric);
    ContactParams cp;
    cp.model = ContactModel::Paper;  // the contact cache is the paper model's
    cp.cacheDistance = k == 0 ? 0.0 : ContactParams().cacheDistance;  // the default, 0.1 um
    e.enableCollisions(cp);
    e.collisions()->settle(e.fabric());
    for (const Yarn& y : e.fabric().yarns)
      if (y.family == YarnFamily::Warp) {
        e.dynamics().fix(y.firstNode);
        e.dynamics().prescribeVelocity(y.firstNode + y.nNodes - 1, Vec3(2, 0, 0));
      }
    const Real dt = 0.7 * e.criticalDt();
    for (int s = 0; s < 400; ++s) {
      e.step(dt);
      cached[k] += e.collisions()->stats.cached;
    }
    pos[k] = e.fabric().pos;
  }
  EXPECT_EQ(cached[0], 0);
  EXPECT_GT(cached[1], 0);
  Real worst = 0;
  for (std::size_t i = 0; i < pos[0].size(); ++i) worst = std::max(worst, (pos[0][i] - pos[1][i]).norm());
  EXPECT_LT(worst, 0.01 * km2_706().warpSection.thickness);
}

// Two tilted pieces of crimped yarn, flattened to the MCD, whose boxes' axis points the other way
// round from their axes at the crossing (the pair that showed it in a ballistic run: CPs 1 and 6 of
// a 6.35 mm ply under a sphere, 49 steps in). The contact must take the local side: with the
// boxes' sign the impulse pushed B through A and the depth was measured to the sections' far sides
// (0.208 mm, against a yarn 0.11 mm thick).
TEST(CPContact, NormalTakesTheSideWhereTheAxesPass) {
  const Real r0 = std::sqrt(3.3424354891806017e-04 * 5.3478967830077872e-05);  // constant area at eps 0.6
  Fabric f;
  f.addYarn({Vec3(0.00040030723604226795, 0.00033533744367069497, -0.00019908385704081396),
             Vec3(0.0011825889836095489, 0.0003054778496736031, -0.0003310878112283988)}, km2Material(), roundSection(r0));
  f.addYarn({Vec3(0.0003735294117647059, -0.0003735294117647059, 5.5e-05),
             Vec3(0.0002468126456741782, 0.00032130821415819586, -0.0002998536906452092)}, km2Material(), roundSection(r0));
  const Vec3 dirs[4] = {Vec3(0.16903738991623307, 0.026736940203719736, 0.9852469217606569),
                        Vec3(-0.16155708790666298, 0.02007478652859792, 0.9866591662235497),
                        Vec3(-0.10291891776910196, 0.4261587933344468, 0.8987749324658343),
                        Vec3(-0.03707497083560495, 0.1474725185289261, 0.9883710349945888)};
  for (Index k = 0; k < 4; ++k) f.secFlat[k] = 0.6, f.secDir[k] = dirs[k];
  Vec3Array t;
  updateSectionFrames(f, t);
  std::vector<OBB> boxes;
  refitBounds(f, t, SectionRule::ConstantArea, 0, boxes);
  const SegmentClosest sc = closestSegmentSegment(f.pos[0], f.pos[1], f.pos[2], f.pos[3]);
  const Vec3 ab = (f.pos[2] + sc.t * (f.pos[3] - f.pos[2])) - (f.pos[0] + sc.s * (f.pos[1] - f.pos[0]));
  const BoxContact box = obbContact(boxes[0], boxes[1], 0, kLateralCos, false);
  ASSERT_TRUE(box.overlap);
  ASSERT_LT(box.normal.dot(ab), 0);  // the scene is the one meant
  CPContact c;
  ASSERT_TRUE(cpContactStatic(f, boxes, 0, 1, 0, SectionRule::ConstantArea, c));
  EXPECT_GT(c.normal.dot(ab), 0);
  // The near sides: the two minor semi-axes (5.35e-5 m each) less the axes' distance along the
  // normal, up to the sections' tilt against it (the ellipses are 6x wider than thick: allow 2x).
  const Real nearSides = 2 * 5.35e-5 - std::abs(ab.dot(c.normal));
  EXPECT_GT(-c.gap, 0);
  EXPECT_LT(-c.gap, 2 * std::max(nearSides, Real(1e-5)));
}
