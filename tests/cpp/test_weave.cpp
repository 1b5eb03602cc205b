// Weave builder (pkg/weave/WeaveBuilder.hpp): the KM2 preset against its datasheet and Peirce,
// crossing clearance for every preset pattern and a random one, seamless replication, mass
// bookkeeping, adaptive resolution (mass, series stiffness and crossings against the uniform
// model), and the ParameterError raised for each kind of invalid input.
#include "core/Errors.hpp"
#include "geom/SegmentDistance.hpp"
#include "weave/WeaveBuilder.hpp"
#include "chain_util.hpp"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

using woven::Fabric;
using woven::Index;
using woven::Pattern;
using woven::Real;
using woven::Vec3;
using woven::Weave;
using woven::WeaveParams;

using woven_test::parameterOf;
using woven_test::rel;

namespace {



// A random 0/1 matrix that is a valid pattern (seeded; invalid draws are rejected).
Pattern randomPattern(std::mt19937& rng) {
  std::uniform_int_distribution<int> size(2, 6), bit(0, 1);
  for (;;) {
    std::vector<std::vector<int>> m(size(rng));
    const int cols = size(rng);
    for (auto& r : m) {
      r.resize(cols);
      for (int& v : r) v = bit(rng);
    }
    try {
      return Pattern(m);
    } catch (const woven::ParameterError&) {
    }
  }
}

// Smallest distance between any two nodes of the fabric, by a sweep along x.
Real minNodeDistance(const Fabric& f) {
  std::vector<Index> order(f.nNodes());
  for (Index i = 0; i < f.nNodes(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](Index a, Index b) { return f.pos[a].x() < f.pos[b].x(); });
  Real best = INFINITY;
  for (std::size_t k = 0; k < order.size(); ++k)
    for (std::size_t q = k + 1; q < order.size(); ++q) {
      if (f.pos[order[q]].x() - f.pos[order[k]].x() >= best) break;
      best = std::min(best, (f.pos[order[q]] - f.pos[order[k]]).norm());
    }
  return best;
}

// Centre-line gap at every crossing, found from the node positions alone: the warp node lying at
// x = (j + 1/2) weftSpacing and the weft node at y = (i + 1/2) warpSpacing; the yarn on top is the
// warp where pattern(i, j) = 1. Returns the smallest gap and counts the crossings found.
Real gapFromNodes(const Weave& w, const WeaveParams& P, long& crossings) {
  const Fabric& f = w.fabric;
  const int NW = static_cast<int>(w.warpYarns.size()), NF = static_cast<int>(w.weftYarns.size());
  std::vector<Real> zWarp(NW * NF, NAN), zWeft(NW * NF, NAN);
  auto crossingIndex = [](Real coord, Real spacing, int count) {
    const Real u = coord / spacing - 0.5;
    const long k = std::lround(u);
    return (std::abs(u - k) < 1e-9 && k >= 0 && k < count) ? k : -1;
  };
  for (int i = 0; i < NW; ++i) {
    const auto& y = f.yarns[w.warpYarns[i]];
    for (Index q = 0; q < y.nNodes; ++q) {
      const long j = crossingIndex(f.pos[y.firstNode + q].x(), P.weftSpacing, NF);
      if (j >= 0) zWarp[i * NF + j] = f.pos[y.firstNode + q].z();
    }
  }
  for (int j = 0; j < NF; ++j) {
    const auto& y = f.yarns[w.weftYarns[j]];
    for (Index q = 0; q < y.nNodes; ++q) {
      const long i = crossingIndex(f.pos[y.firstNode + q].y(), P.warpSpacing, NW);
      if (i >= 0) zWeft[i * NF + j] = f.pos[y.firstNode + q].z();
    }
  }
  Real gap = INFINITY;
  crossings = 0;
  for (int i = 0; i < NW; ++i)
    for (int j = 0; j < NF; ++j) {
      const Real zw = zWarp[i * NF + j], zf = zWeft[i * NF + j];
      if (std::isnan(zw) || std::isnan(zf)) continue;
      ++crossings;
      gap = std::min(gap, P.pattern.warpOver(i % P.pattern.rows(), j % P.pattern.cols()) ? zw - zf : zf - zw);
    }
  return gap;
}

// Smallest 3D distance between any warp CP and any weft CP of the fabric (brute force).
Real minWarpWeftDistance(const Weave& w) {
  const Fabric& f = w.fabric;
  Real best = INFINITY;
  for (Index yw : w.warpYarns)
    for (Index yf : w.weftYarns) {
      const auto &A = f.yarns[yw], &B = f.yarns[yf];
      for (Index a = A.firstNode; a + 1 < A.firstNode + A.nNodes; ++a)
        for (Index b = B.firstNode; b + 1 < B.firstNode + B.nNodes; ++b)
          best = std::min(best, woven::closestSegmentSegment(f.pos[a], f.pos[a + 1], f.pos[b], f.pos[b + 1]).distance);
    }
  return best;
}

}  // namespace

TEST(Weave, Km2ArealDensityAndCrimp) {
  const WeaveParams P = woven::km2_706();
  const Weave w = woven::buildWeave(P);
  const auto& S = w.summary;
  // Datasheet: KM2 style 706 weighs 180 g/m^2; within 1 %.
  EXPECT_LT(rel(S.arealDensity, 0.180), 0.01) << S.arealDensity;
  // Closed form: each family puts rho*A*(1 + crimp) of yarn per unit length over each spacing.
  const Real closed = P.warpMaterial.rho * P.warpMaterial.area * (1 + S.warpCrimpBuilt) / P.warpSpacing +
                      P.weftMaterial.rho * P.weftMaterial.area * (1 + S.weftCrimpBuilt) / P.weftSpacing;
  EXPECT_LT(rel(S.arealDensity, closed), 1e-9);
  // The CP chords cut Peirce's arcs: built crimp within 3 % (relative) of Peirce's crimp.
  EXPECT_GT(S.warpPeirce.crimp(), 0);
  EXPECT_LT(rel(S.warpCrimpBuilt, S.warpPeirce.crimp()), 0.03) << S.warpCrimpBuilt << " vs " << S.warpPeirce.crimp();
  EXPECT_LT(rel(S.weftCrimpBuilt, S.weftPeirce.crimp()), 0.03) << S.weftCrimpBuilt << " vs " << S.weftPeirce.crimp();
}

TEST(Weave, CrossingsClearForEveryPatternAndResolution) {
  std::mt19937 rng(20240611);
  const std::vector<std::pair<std::string, Pattern>> patterns = {
      {"plain", Pattern::plain()},          {"twill 2/1", Pattern::twill(2, 1)},
      {"twill 3/1", Pattern::twill(3, 1)},  {"satin 5/2", Pattern::satin(5, 2)},
      {"basket 2", Pattern::basket(2)},     {"random", randomPattern(rng)}};
  for (const auto& [name, pattern] : patterns)
    for (int cp : {1, 2, 3, 4, 8})
      for (int nx : {1, 3})
        for (int ny : {1, 3}) {
          SCOPED_TRACE(name + ", cpPerSpan " + std::to_string(cp) + ", nx " + std::to_string(nx) + ", ny " +
                       std::to_string(ny));
          WeaveParams P = woven::km2_706();
          P.pattern = pattern, P.cpPerSpan = cp, P.nx = nx, P.ny = ny;
          const Weave w = woven::buildWeave(P);
          const auto& S = w.summary;
          ASSERT_EQ(S.warpYarns, ny * pattern.rows());
          ASSERT_EQ(S.weftYarns, nx * pattern.cols());
          // Required: centre lines at a crossing at least (t_warp + t_weft)/2 apart.
          EXPECT_EQ(S.requiredGap, 0.5 * (P.warpSection.thickness + P.weftSection.thickness));
          EXPECT_GE(S.minVerticalGap, S.requiredGap - 1e-9);
          // Two straight CPs leave each crossing node, tilted at most by the weave angle (the
          // chord slope of Peirce's profile never exceeds tan(theta)): lines through points g
          // apart along z with directions (1, 0, a) and (0, 1, b) are g/sqrt(1 + a^2 + b^2) apart.
          const Real tw = std::tan(S.warpPeirce.theta), tf = std::tan(S.weftPeirce.theta);
          EXPECT_GE(S.minChainClearance, S.requiredGap / std::sqrt(1 + tw * tw + tf * tf) - 1e-12);
          EXPECT_LE(S.minChainClearance, S.minVerticalGap + 1e-15);  // the crossing nodes themselves
          // Independently of the summary: the gap measured on the nodes at every crossing.
          long crossings = 0;
          const Real gap = gapFromNodes(w, P, crossings);
          EXPECT_EQ(crossings, long(S.warpYarns) * S.weftYarns);
          EXPECT_GE(gap, S.requiredGap - 1e-9);
          EXPECT_NEAR(gap, S.minVerticalGap, 1e-15);
          // One repeat: every warp CP against every weft CP, not only those near a crossing.
          if (nx == 1 && ny == 1) {
            EXPECT_GE(minWarpWeftDistance(w), S.requiredGap / std::sqrt(1 + tw * tw + tf * tf) - 1e-12);
          }
        }
}

TEST(Weave, ReplicationIsSeamless) {
  std::mt19937 rng(7);
  for (const Pattern& pattern : {Pattern::plain(), Pattern::twill(2, 1), Pattern::satin(5, 2), randomPattern(rng)})
    for (int cp : {1, 2, 3, 4}) {
      SCOPED_TRACE(std::to_string(pattern.rows()) + "x" + std::to_string(pattern.cols()) + " pattern, cpPerSpan " +
                   std::to_string(cp));
      WeaveParams P = woven::km2_706();
      P.pattern = pattern, P.cpPerSpan = cp, P.nx = 3, P.ny = 3;
      const Weave w = woven::buildWeave(P);
      const Fabric& f = w.fabric;
      Index nodes = 0, elems = 0;
      for (const auto& y : f.yarns) nodes += y.nNodes, elems += y.nElems;
      EXPECT_EQ(f.nNodes(), nodes);
      EXPECT_EQ(f.nElems(), elems);
      EXPECT_EQ(w.summary.nodes, nodes);
      EXPECT_EQ(w.summary.elements, elems);
      // No duplicate nodes where repeats meet (nodes are ~ spacing/cpPerSpan = 0.19 mm apart).
      EXPECT_GT(minNodeDistance(f), 1e-9);

      // Periodicity: shifting by one repeat (n*C nodes of a warp, n*R of a weft) moves a node by
      // C*weftSpacing in x (R*warpSpacing in y); positions to 1e-12 m (coordinates ~1e-2 m carry
      // rounding ~1e-18 m), rest lengths to 1e-12 relative.
      const int n = cp, C = pattern.cols(), R = pattern.rows();
      auto checkYarn = [&](Index yi, int period, const Vec3& shift) {
        const auto& y = f.yarns[yi];
        for (Index k = 0; k + period < y.nNodes; ++k) {
          const Vec3 d = f.pos[y.firstNode + k + period] - (f.pos[y.firstNode + k] + shift);
          ASSERT_LT(d.norm(), 1e-12) << "yarn " << yi << " node " << k;
        }
        for (Index k = 0; k + period < y.nElems; ++k)
          ASSERT_LT(rel(f.restLength[y.firstElem + k + period], f.restLength[y.firstElem + k]), 1e-12)
              << "yarn " << yi << " element " << k;
      };
      for (Index yi : w.warpYarns) checkYarn(yi, n * C, Vec3(C * P.weftSpacing, 0, 0));
      for (Index yi : w.weftYarns) checkYarn(yi, n * R, Vec3(0, R * P.warpSpacing, 0));

      // Mass bookkeeping: the lumped node masses add up to sum over elements of rho*A*l0.
      Real elementMass = 0;
      for (Index e = 0; e < f.nElems(); ++e) {
        const auto& m = f.materials[f.yarns[f.elemYarn[e]].material];
        elementMass += m.rho * m.area * f.restLength[e];
      }
      EXPECT_LT(rel(f.totalMass(), elementMass), 1e-12);
    }
}

// Adaptive resolution: cpPerSpan CPs near the fine centre, cpCoarse elsewhere.
TEST(Weave, AdaptiveKeepsMassStiffnessAndCrossings) {
  for (const Pattern& pattern : {Pattern::plain(), Pattern::twill(2, 1)})
    for (auto [fine, coarse] : {std::pair{4, 1}, std::pair{3, 2}, std::pair{5, 3}}) {
      SCOPED_TRACE(std::to_string(pattern.rows()) + "x" + std::to_string(pattern.cols()) + " pattern, " +
                   std::to_string(fine) + " / " + std::to_string(coarse) + " CPs");
      WeaveParams P = woven::km2_706();
      P.pattern = pattern, P.nx = P.ny = 6, P.cpPerSpan = fine;
      const Weave uf = woven::buildWeave(P);
      WeaveParams Pc = P;
      Pc.cpPerSpan = coarse;
      const Weave uc = woven::buildWeave(Pc);
      P.fineRadius = 0.25 * uf.summary.lengthX, P.cpCoarse = coarse;
      const Weave a = woven::buildWeave(P);
      const Fabric &fa = a.fabric, &ff = uf.fabric;
      // Some spans fine, some coarse; element count in between.
      ASSERT_GT(a.summary.fineSpans, 0);
      ASSERT_LT(a.summary.fineSpans, a.summary.spans);
      EXPECT_GT(fa.nElems(), uc.fabric.nElems());
      EXPECT_LT(fa.nElems(), ff.nElems());
      // The shortest element is a fine one: the critical time step is the uniform fine model's.
      EXPECT_NEAR(a.summary.minElementLength, uf.summary.minElementLength, 1e-15);

      // Lumping at the seams: each node carries rho*A*l/2 of each neighbouring element, K = E*A/l0.
      for (const auto& y : fa.yarns) {
        const auto& m = fa.materials[y.material];
        for (Index k = 0; k < y.nNodes; ++k) {
          const Real l = (k > 0 ? fa.restLength[y.firstElem + k - 1] : 0) + (k + 1 < y.nNodes ? fa.restLength[y.firstElem + k] : 0);
          ASSERT_LT(rel(fa.mass[y.firstNode + k], 0.5 * m.rho * m.area * l), 1e-12);
        }
        for (Index e = y.firstElem; e < y.firstElem + y.nElems; ++e)
          ASSERT_LT(rel(fa.stiffness[e], m.E * m.area / fa.restLength[e]), 1e-12);
      }
      // Each yarn's mass and series stiffness against the uniform fine model's. They differ only by
      // the chain length. Both chains are polylines inscribed in Peirce's centre line through the same
      // crossing and end nodes, so on each span each lies between the chord and the arc: they differ
      // by at most (arc - chord) per span, i.e. (Peirce's crimp - the 1-CP built crimp) per projected
      // length (averaged over the pattern repeat; the two partial end spans are allowed 3 spans more).
      Pc.cpPerSpan = 1;
      const Weave u1 = woven::buildWeave(Pc);
      const Real dCrimp = std::max(u1.summary.warpPeirce.crimp() - u1.summary.warpCrimpBuilt,
                                   u1.summary.weftPeirce.crimp() - u1.summary.weftCrimpBuilt);
      Real maxDiff = 0;
      ASSERT_EQ(fa.nYarns(), ff.nYarns());
      for (Index yi = 0; yi < fa.nYarns(); ++yi) {
        const auto &ya = fa.yarns[yi], &yf = ff.yarns[yi];
        Real ma = 0, mf = 0, ca = 0, cf = 0, proj = std::abs(fa.pos[ya.firstNode + ya.nNodes - 1].x() - fa.pos[ya.firstNode].x()) +
                                              std::abs(fa.pos[ya.firstNode + ya.nNodes - 1].y() - fa.pos[ya.firstNode].y());
        for (Index k = 0; k < ya.nNodes; ++k) ma += fa.mass[ya.firstNode + k];
        for (Index k = 0; k < yf.nNodes; ++k) mf += ff.mass[yf.firstNode + k];
        for (Index e = 0; e < ya.nElems; ++e) ca += 1 / fa.stiffness[ya.firstElem + e];
        for (Index e = 0; e < yf.nElems; ++e) cf += 1 / ff.stiffness[yf.firstElem + e];
        // Both ends of the yarn where the uniform model's are.
        EXPECT_LT((fa.pos[ya.firstNode] - ff.pos[yf.firstNode]).norm(), 1e-15);
        EXPECT_LT((fa.pos[ya.firstNode + ya.nNodes - 1] - ff.pos[yf.firstNode + yf.nNodes - 1]).norm(), 1e-15);
        const Real length = ma / (fa.materials[ya.material].rho * fa.materials[ya.material].area);
        const Real bound = dCrimp * (proj + 3 * P.weftSpacing) / length;
        EXPECT_LE(std::abs(ma - mf) / mf, bound) << "yarn " << yi;
        EXPECT_LE(std::abs(1 / ca - 1 / cf) * cf, bound) << "yarn " << yi;
        maxDiff = std::max(maxDiff, std::abs(ma - mf) / mf);
      }
      EXPECT_LT(maxDiff, 1e-4);
      EXPECT_GT(dCrimp, 0);  // the bound is not vacuous: the resolutions differ

      // Crossings: a node on every one, at the required gap; chains clear as in the uniform test.
      long crossings = 0;
      const Real gap = gapFromNodes(a, P, crossings);
      EXPECT_EQ(crossings, long(a.summary.warpYarns) * a.summary.weftYarns);
      EXPECT_NEAR(gap, a.summary.requiredGap, 1e-15);
      const Real tw = std::tan(a.summary.warpPeirce.theta), tf = std::tan(a.summary.weftPeirce.theta);
      EXPECT_GE(minWarpWeftDistance(a), a.summary.requiredGap / std::sqrt(1 + tw * tw + tf * tf) - 1e-12);
    }
  // fineRadius < 0 is the uniform model, bit for bit; so is a radius that covers the whole fabric.
  WeaveParams P = woven::km2_706();
  P.nx = P.ny = 3;
  const Weave u = woven::buildWeave(P);
  P.fineRadius = 1.0;
  const Weave all = woven::buildWeave(P);
  ASSERT_EQ(u.fabric.nNodes(), all.fabric.nNodes());
  for (Index i = 0; i < u.fabric.nNodes(); ++i) ASSERT_EQ(u.fabric.pos[i], all.fabric.pos[i]);
}

TEST(Weave, BadInputNamesTheParameter) {
  auto build = [](std::function<void(WeaveParams&)> change) {
    return parameterOf([&] {
      WeaveParams P = woven::km2_706();
      change(P);
      woven::buildWeave(P);
    });
  };
  EXPECT_EQ(build([](WeaveParams& P) { P.warpSection.width = 1.1 * P.warpSpacing; }), "warp_spacing");
  EXPECT_EQ(build([](WeaveParams& P) { P.weftSection.width = 1.1 * P.weftSpacing; }), "weft_spacing");
  EXPECT_EQ(build([](WeaveParams& P) { P.cpPerSpan = 0; }), "cp_per_span");
  EXPECT_EQ(build([](WeaveParams& P) { P.fineRadius = NAN; }), "fine_radius");
  EXPECT_EQ(build([](WeaveParams& P) { P.fineRadius = 1e-3, P.cpCoarse = 0; }), "cp_coarse");
  EXPECT_EQ(build([](WeaveParams& P) { P.fineRadius = 1e-3, P.cpCoarse = P.cpPerSpan + 1; }), "cp_coarse");
  EXPECT_EQ(build([](WeaveParams& P) { P.fineX = INFINITY; }), "fine_x");
  EXPECT_EQ(build([](WeaveParams& P) { P.nx = 0; }), "nx");
  EXPECT_EQ(build([](WeaveParams& P) { P.warpMaterial.E = -90e9; }), "warp_E");
  EXPECT_EQ(build([](WeaveParams& P) { P.weftMaterial.rho = -1440; }), "weft_rho");
  EXPECT_EQ(build([](WeaveParams& P) { P.warpSection.thickness = -0.11e-3; }), "warp_thickness");
  EXPECT_EQ(build([](WeaveParams& P) { P.weftSection.thickness = 0; }), "weft_thickness");
  EXPECT_EQ(build([](WeaveParams& P) { P.warpCrimp = 1.5; }), "warp_crimp");
  // Crimp 0.1 % each: Peirce heights far below (t_warp + t_weft)/2 each, the yarns would overlap.
  EXPECT_EQ(build([](WeaveParams& P) { P.warpCrimp = P.weftCrimp = 0.001; }), "warp_crimp");
  EXPECT_EQ(build([](WeaveParams& P) { P.weftCrimp = 1.0; }), "weft_crimp");
}

TEST(Weave, OneGivenCrimpIsCompletedToTouchingYarns) {
  // Only the weft crimp given (too small on its own): the warp takes the rest of the height,
  // h_warp = D - h_weft, so the crossings still clear and the warp crimp follows from Peirce.
  WeaveParams P = woven::km2_706();
  P.weftCrimp = 0.001;
  const Weave w = woven::buildWeave(P);
  const auto& S = w.summary;
  const Real D = P.warpSection.thickness + P.weftSection.thickness;
  EXPECT_LT(rel(S.weftPeirce.crimp(), 0.001), 1e-9);
  EXPECT_LT(rel(S.warpPeirce.h + S.weftPeirce.h, D), 1e-12);
  EXPECT_GE(S.minVerticalGap, S.requiredGap - 1e-9);
}
