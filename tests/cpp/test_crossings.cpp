// The persistent crossing contact (engine/CrossingContacts, geom/YarnCurve, GapFunction's
// crossingGap): its line against the quadratic Bezier it is meant to be, its gap against the closed
// form distance of two lines and its gradient (the row's stencil) against finite differences; a
// carried crossing against a fresh measure; each hand-back rule on two straight yarns, with no jump
// in the overlap; and no chord pair of a live crossing in the candidates or the contacts (the broad
// phase's output; narrow phase, rows and projection read the contacts).
#include "body_util.hpp"
#include "chain_util.hpp"
#include "engine/FabricEngine.hpp"
#include "geom/GapFunction.hpp"
#include "geom/YarnCurve.hpp"
#include "weave/WeaveBuilder.hpp"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

using namespace woven;
using namespace woven_test;

namespace {

constexpr Real kL = 0.25e-3;  // CP length [m]
constexpr int kCPs = 16;      // per yarn: 4 mm

// Yarn A along x (z = zA(x)), yarn B along y at height h, shifted to x = xB; one CP each 0.25 mm.
Fabric twoYarns(Real h, Real xB, Real crimpA = 0) {
  Fabric f;
  Vec3Array a, b;
  for (int k = 0; k <= kCPs; ++k) {
    const Real u = (k - kCPs / 2) * kL;
    a.push_back(Vec3(u, 0.01e-3, (k % 2 ? -crimpA : crimpA)));  // a peak at even nodes
    b.push_back(Vec3(xB, u, h));
  }
  f.addYarn(a, km2Material(), YarnSection());
  f.addYarn(b, km2Material(), YarnSection());
  return f;
}

// The lines' distance at their closest places near (a, b), converged.
Real lineDistance(const Fabric& f, YarnPlace a, YarnPlace b, CPContact* out = nullptr) {
  EXPECT_TRUE(closestPlaces(f, a, b, 1e-15, 50));
  CPContact c;
  crossingGap(f, a.cp, a.s, b.cp, b.s, SectionRule::Paper, Vec3::UnitZ(), c);
  if (out) *out = c;
  return c.gap + c.hA + c.hB;  // the axes' signed distance (GapFunction: capMeasure)
}

}  // namespace

// Around an inner node the line is the quadratic Bezier (1-u)^2 Pa + 2u(1-u) x_k + u^2 Pb over
// lambda = kBlend r0 along each chord (YarnCurve.hpp), written out here from the nodes alone; away
// from the corners it is the chord. Its derivative in s against central differences.
TEST(YarnCurve, IsTheRoundedChainLine) {
  Fabric f = twoYarns(1e-3, 0, 30e-6);
  const Index e = 8, k = f.elem0[e];  // CP 8 starts at node 8, a corner of 2 x 13.5 degrees
  const Real Lp = f.restLength[e - 1], L = f.restLength[e];
  const Real lam = std::min(kBlend * f.secRadius[k], kBlendMax * std::min(Lp, L));
  const Vec3 Pa = f.pos[k] + (lam / Lp) * (f.pos[k - 1] - f.pos[k]), Pb = f.pos[k] + (lam / L) * (f.pos[k + 1] - f.pos[k]);
  for (Real u : {0.5, 0.6, 0.75, 0.9, 1.0}) {
    const Vec3 bez = (1 - u) * (1 - u) * Pa + 2 * u * (1 - u) * f.pos[k] + u * u * Pb;
    const Real s = (u - 0.5) * 2 * lam / L;  // Pb at s = lam / L on CP e; the node at s = 0
    EXPECT_LT((yarnCurveAt(f, e, s).x - bez).norm(), 1e-15) << "u = " << u;
    Index node[3];
    Real w[3];
    const int m = yarnCurveWeights(f, e, s, node, w);
    Vec3 x = Vec3::Zero();
    Real sum = 0;
    for (int q = 0; q < m; ++q) {
      x += w[q] * f.pos[node[q]], sum += w[q];
      EXPECT_GE(w[q], 0);
    }
    EXPECT_NEAR(sum, 1, 1e-15);
    EXPECT_LT((x - bez).norm(), 1e-15);
  }
  const Real mid = 0.5;  // the chord between the corners
  EXPECT_LT((yarnCurveAt(f, e, mid).x - 0.5 * (f.pos[k] + f.pos[k + 1])).norm(), 1e-15);
  for (Real s : {0.01, 0.05, 0.3, 0.97}) {
    const Real ds = 1e-6;
    const Vec3 fd = (yarnCurveAt(f, e, s + ds).x - yarnCurveAt(f, e, s - ds).x) / (2 * ds);
    EXPECT_LT((yarnCurveAt(f, e, s).d1 - fd).norm(), 1e-8 * kL) << "s = " << s;
  }
}

// Two straight yarns crossing: the crossing's axis distance is the lines' closed-form distance
// |(pB - pA) . (u x v)| / |u x v|, at any skew; its normal is that of the common perpendicular.
TEST(CrossingGap, StraightYarnsMatchTheClosedForm) {
  for (Real tilt : {0.0, 0.2, 0.5}) {
    Fabric f = twoYarns(0.15e-3, 0.037e-3);
    for (int k = 0; k <= kCPs; ++k) f.pos[kCPs + 1 + k].x() += tilt * (k - kCPs / 2) * kL;  // B skewed
    CPContact c;
    const Real d = lineDistance(f, {7, 0.6}, {kCPs + 7, 0.6}, &c);
    const Vec3 u = f.pos[1] - f.pos[0], v = f.pos[kCPs + 2] - f.pos[kCPs + 1], n = u.cross(v).normalized();
    const Real exact = std::abs((f.pos[kCPs + 1] - f.pos[0]).dot(n));
    EXPECT_NEAR(d, exact, 1e-15) << "tilt " << tilt;
    EXPECT_NEAR(std::abs(c.normal.dot(n)), 1, 1e-12);
  }
}

// The row's gradient: d(distance)/dx_k = w_k normal for each node of the stencil (A's weights
// negative), 0 for every other node, against central differences of the distance re-converged at the
// moved positions (the places are a minimum: the envelope theorem). Crimped A, B crossing at A's
// node so that the rounded corner is in the stencil (three nodes of A), and off it.
TEST(CrossingGap, GradientIsTheStencil) {
  for (Real xB : {0.003e-3, 0.11e-3}) {
    Fabric f = twoYarns(0.15e-3, xB, 25e-6);
    CPContact c;
    const YarnPlace a0{8, 0.1}, b0{kCPs + 8, 0.05};
    lineDistance(f, a0, b0, &c);
    if (xB < 0.01e-3) {
      EXPECT_EQ(c.nStencilA, 3) << "the corner's three nodes";
    }
    Real grad[2 * (kCPs + 1)][3] = {};
    for (int q = 0; q < c.nStencil; ++q)
      for (int j = 0; j < 3; ++j) grad[c.stencilNode[q]][j] += c.stencilW[q] * c.normal[j];
    const Real eps = 1e-10;
    for (Index i = 0; i < f.nNodes(); ++i)
      for (int j = 0; j < 3; ++j) {
        Fabric g = f;
        g.pos[i][j] += eps;
        const Real up = lineDistance(g, a0, b0);
        g.pos[i][j] -= 2 * eps;
        const Real down = lineDistance(g, a0, b0);
        EXPECT_NEAR((up - down) / (2 * eps), grad[i][j], 2e-5) << "xB " << xB << " node " << i << " axis " << j;
      }
  }
}

namespace {

// Two straight yarns touching (B on A, their sections flattened to fit by settle), A's nodes fixed,
// B's nodes moved at velocity v(x) (prescribed each step). Returns the engine and reports, per step,
// the crossings live and the largest overlap between the two yarns' contacts.
struct TwoYarnRun {
  std::unique_ptr<FabricEngine> e;
  Real dt = 0;
  explicit TwoYarnRun(Real xB = 0.037e-3) {
    e = std::make_unique<FabricEngine>(twoYarns(0.12e-3 - 1e-6, xB));
    e->enableCollisions(ContactParams(), BroadPhase::Grid);
    e->collisions()->settle(e->fabric());
    for (Index i = 0; i <= kCPs; ++i) e->dynamics().fix(i);
    dt = 0.5 * e->criticalDt();
  }
  // One step with B's nodes at v(x); returns the largest overlap of the listed contacts [m] (0: none).
  template <class V>
  Real step(V&& v) {
    const Fabric& f = e->fabric();
    for (Index i = kCPs + 1; i < f.nNodes(); ++i) e->dynamics().prescribeVelocity(i, v(f.pos[i]));
    e->step(dt);
    Real worst = 0;
    for (const CPContact& c : e->collisions()->contacts()) worst = std::max(worst, -c.gap);
    return worst;
  }
  long live() const { return static_cast<long>(e->collisions()->crossings().crossings().size()); }
  long handedBack(HandBack why) const { return e->collisions()->crossings().counts.handedBack[static_cast<int>(why)]; }
};

// Runs until the crossing is handed back by `why` (at most maxSteps); checks that it formed, that it
// went by that rule alone, and that the overlap did not jump at the hand-back (the chords' pair
// takes over where the crossing left: straight yarns, the same distance).
template <class V>
void handedBackWithoutAJump(TwoYarnRun& r, HandBack why, int maxSteps, V&& v) {
  Real before = r.step(v);
  ASSERT_EQ(r.live(), 1) << "the crossing formed at the first step";
  for (int s = 0; s < maxSteps && r.live() == 1; ++s) {
    const Real now = r.step(v);
    if (r.live() == 0) {
      EXPECT_LE(now, before + 0.2e-6) << "overlap after the hand-back against before it";
    }
    before = now;
  }
  EXPECT_EQ(r.live(), 0) << "handed back within " << maxSteps << " steps";
  for (int k = 0; k < 5; ++k) EXPECT_EQ(r.handedBack(static_cast<HandBack>(k)), k == static_cast<int>(why) ? 1 : 0) << "rule " << k;
}

}  // namespace

TEST(CrossingHandBack, Separation) {
  TwoYarnRun r;
  handedBackWithoutAJump(r, HandBack::Separation, 4000, [](const Vec3&) { return Vec3(0, 0, 50); });
  EXPECT_EQ(r.step([](const Vec3&) { return Vec3(0, 0, 50); }), 0) << "no contact once apart";
}

TEST(CrossingHandBack, Turn) {
  TwoYarnRun r;
  const Vec3 centre(0.037e-3, 0.01e-3, 0);
  // B turns about the crossing's vertical at 6e4 rad/s: 45 degrees in ~ 13 us
  handedBackWithoutAJump(r, HandBack::Turn, 20000, [&](const Vec3& x) { return Vec3(0, 0, 6e4).cross(x - centre); });
}

TEST(CrossingHandBack, SlideOffTheYarnsEnd) {
  TwoYarnRun r;
  // B slides along A at 100 m/s: the crossing's place on A walks CP to CP until A ends at 2 mm
  handedBackWithoutAJump(r, HandBack::Slide, 20000, [](const Vec3&) { return Vec3(100, 0, 0); });
  EXPECT_GE(r.e->collisions()->crossings().counts.moved, kCPs / 2 - 1) << "it walked CP to CP first";
}

TEST(CrossingHandBack, Break) {
  TwoYarnRun r;
  auto still = [](const Vec3&) { return Vec3(0, 0, 0); };
  r.step(still);
  ASSERT_EQ(r.live(), 1);
  const Index cp = r.e->collisions()->crossings().crossings()[0].a.cp;
  Fabric& f = r.e->fabric();
  f.alive[cp] = 0, f.stiffness[cp] = 0, f.damping[cp] = 0;  // as Breakage leaves a broken CP
  r.step(still);
  EXPECT_EQ(r.live(), 0);
  EXPECT_EQ(r.handedBack(HandBack::Break), 1);
}

// Formation looks one CP on: a crossing whose place lies near a node beside a CP kinked beyond
// kKinkDeg would be handed back as soon as tracking walks it there (traced at 4 CPs per span: a
// crossing formed and handed back at every step), so the general pipeline keeps its pairs. Yarn A
// straight through the place's CP and the one beyond, bent down by 40 degrees at the node before
// the CP next to the place; the same yarns straight form the crossing.
TEST(Crossings, NoneFormsBesideAKinkedCP) {
  const auto run = [](Real bendDeg) {
    Fabric f = twoYarns(0.12e-3 - 1e-6, 0.01e-3);  // B over A at x = 10 um: A's CP 8 at s = 0.04
    const Real c = std::cos(bendDeg * 3.14159265358979323846 / 180), s = std::sin(bendDeg * 3.14159265358979323846 / 180);
    const Vec3 knee = f.pos[7];  // A's node 7: CP 7 (nodes 7, 8) straight on, CP 6 and before bent down
    for (Index i = 0; i < 7; ++i) {
      const Real back = knee.x() - f.pos[i].x();
      f.pos[i] = Vec3(knee.x() - c * back, f.pos[i].y(), knee.z() - s * back);
    }
    FabricEngine e(f);
    e.enableCollisions(ContactParams(), BroadPhase::Grid);
    e.collisions()->settle(e.fabric());
    for (Index i = 0; i < e.fabric().nNodes(); ++i) e.dynamics().fix(i);
    const Real dt = 0.5 * e.criticalDt();
    Real worst = 0;
    for (int k = 0; k < 20; ++k) {
      e.step(dt);
      for (const CPContact& q : e.collisions()->contacts()) worst = std::max(worst, -q.gap);
    }
    return std::make_pair(e.collisions()->crossings().counts.formed, worst);
  };
  const auto straight = run(0), bent = run(40);
  EXPECT_EQ(straight.first, 1) << "the straight yarns form their crossing once";
  EXPECT_EQ(bent.first, 0) << "none formed beside the kinked CP (one formed without the rule)";
  EXPECT_LE(bent.second, 1e-6) << "the chord pairs keep the yarns apart";
}

namespace {

// A 13.4 mm KM2 ply of `cpPerSpan` CPs per span (ends clamped, sections settled) and a 3 mm, 1 g cube
// 0.2 mm above its middle at 300 m/s: crossings carried, disturbed and handed back within 150 steps.
std::unique_ptr<FabricEngine> struckPly(int cpPerSpan) {
  WeaveParams p = km2_706();
  p.nx = p.ny = 9;
  p.cpPerSpan = cpPerSpan;
  auto engine = std::make_unique<FabricEngine>(buildWeave(p).fabric);
  FabricEngine& e = *engine;
  e.enableCollisions(ContactParams(), BroadPhase::Grid);
  e.collisions()->settle(e.fabric());
  for (const Yarn& y : e.fabric().yarns) e.dynamics().fix(y.firstNode), e.dynamics().fix(y.firstNode + y.nNodes - 1);
  e.collisions()->bodies.push_back(cubeAbove(e.fabric(), 1.5e-3, 1e-3, 0.2e-3, Vec3(0, 0, -300)));
  return engine;
}

}  // namespace

// A carried crossing against a fresh measure: in the struck ply (a cube at 300 m/s, 120 steps: the
// yarns move up to 3 um a step, slide and flatten), each live crossing's places, one Newton step
// behind the positions, give the lines' distance no less than the converged closest places do (those
// are the minimum) and within 1 um of it (0.8 % of the thickness; measured: p50 0.009, p90 0.11,
// largest 0.34 um).
TEST(Crossings, CarriedMatchesAFreshMeasure) {
  auto engine = struckPly(2);
  FabricEngine& e = *engine;
  const Real dt = 0.7 * e.criticalDt();
  for (int s = 0; s < 120; ++s) e.step(dt);
  const Fabric& f = e.fabric();
  std::vector<Real> err;
  for (const Crossing& x : e.collisions()->crossings().crossings()) {
    CPContact c;
    crossingGap(f, x.a.cp, x.a.s, x.b.cp, x.b.s, SectionRule::Paper, x.normal, c);
    const Real carried = c.gap + c.hA + c.hB;
    YarnPlace a = x.a, b = x.b;
    if (!closestPlaces(f, a, b, 1e-15, 50)) continue;
    crossingGap(f, a.cp, a.s, b.cp, b.s, SectionRule::Paper, x.normal, c);
    const Real fresh = c.gap + c.hA + c.hB;
    EXPECT_GE(carried, fresh - 1e-15) << "the converged places are the lines' closest";
    err.push_back(carried - fresh);
  }
  ASSERT_GT(err.size(), 200u);
  std::sort(err.begin(), err.end());
  std::printf("carried - fresh: p50 %.3g p90 %.3g p99 %.3g max %.3g um of %zu\n", 1e6 * err[err.size() / 2],
              1e6 * err[err.size() * 9 / 10], 1e6 * err[err.size() * 99 / 100], 1e6 * err.back(), err.size());
  EXPECT_LT(err[err.size() / 2], 0.05e-6) << "median";
  EXPECT_LT(err.back(), 1e-6) << "largest";
}

// No chord pair of a live crossing reaches a stage: in the struck ply after 150 steps (crossings
// formed, some handed back, the cube among them), no candidate pair and no listed contact other than
// the crossing's own joins CPs of one crossing's footprint (its CPs on each yarn).
TEST(Crossings, NoChordPairOfALiveCrossingReachesAStage) {
  auto engine = struckPly(1);
  FabricEngine& e = *engine;
  const Real dt = 0.7 * e.criticalDt();
  long checked = 0;
  for (int s = 0; s < 150; ++s) {
    e.step(dt);
    if (s % 10) continue;
    const CollisionStage& st = *e.collisions();
    auto covered = [&](Index a, Index b) {
      for (const Crossing& x : st.crossings().crossings())
        if ((a >= x.fa0 && a <= x.fa1 && b >= x.fb0 && b <= x.fb1) || (b >= x.fa0 && b <= x.fa1 && a >= x.fb0 && a <= x.fb1))
          return true;
      return false;
    };
    for (const CPPair& q : st.candidates()) EXPECT_FALSE(covered(q.a, q.b)) << "candidate " << q.a << "-" << q.b << " step " << s;
    for (const CPContact& c : st.contacts())
      if (c.kind != ContactKind::Crossing) {
        EXPECT_FALSE(covered(c.cpA, c.cpB)) << "contact " << c.cpA << "-" << c.cpB << " step " << s;
      }
    checked += static_cast<long>(st.crossings().crossings().size());
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(e.collisions()->crossings().counts.handedBack[static_cast<int>(HandBack::Break)] +
                e.collisions()->crossings().counts.handedBack[static_cast<int>(HandBack::Separation)] +
                e.collisions()->crossings().counts.handedBack[static_cast<int>(HandBack::Kink)] +
                e.collisions()->crossings().counts.handedBack[static_cast<int>(HandBack::Slide)],
            0)
      << "the cube disturbed some crossings";
}
