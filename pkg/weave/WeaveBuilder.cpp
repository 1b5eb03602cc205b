#include "weave/WeaveBuilder.hpp"
#include "core/Errors.hpp"
#include "geom/SegmentDistance.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

void WeaveParams::validate() const {
  require(nx >= 1 && nx <= 100000, "nx", nx, "[1, 100000]");
  require(ny >= 1 && ny <= 100000, "ny", ny, "[1, 100000]");
  require(cpPerSpan >= 1 && cpPerSpan <= 1000, "cp_per_span", cpPerSpan, "[1, 1000] CPs between crossings");
  require(!std::isnan(fineRadius) && fineRadius < INFINITY, "fine_radius", fineRadius,
          "[0, inf) m for adaptive resolution, < 0 for uniform cp_per_span");
  if (fineRadius >= 0)
    require(cpCoarse >= 1 && cpCoarse <= cpPerSpan, "cp_coarse", cpCoarse,
            "[1, cp_per_span = " + std::to_string(cpPerSpan) + "] CPs between crossings outside fine_radius");
  require(std::isnan(fineX) || std::isfinite(fineX), "fine_x", fineX, "finite m, or NaN for the fabric's middle");
  require(std::isnan(fineY) || std::isfinite(fineY), "fine_y", fineY, "finite m, or NaN for the fabric's middle");
  warpSection.validate("warp_");
  weftSection.validate("weft_");
  warpMaterial.validate("warp_");
  weftMaterial.validate("weft_");
  require(std::isfinite(warpSpacing) && warpSpacing > 0 && warpSpacing <= 1, "warp_spacing", warpSpacing, "(0, 1] m");
  require(std::isfinite(weftSpacing) && weftSpacing > 0 && weftSpacing <= 1, "weft_spacing", weftSpacing, "(0, 1] m");
  // Size before anything is allocated: nx = ny = 100000 passed the per-key ranges and ended in an
  // allocation failure with an empty message.
  const Real nodes = estimatedNodes();
  require(nodes <= kMaxWeaveNodes, nx >= ny ? "nx" : "ny", nx >= ny ? nx : ny,
          "nx, ny and cp_per_span giving at most " + fmt(kMaxWeaveNodes) + " nodes (about " +
              fmt(kMaxWeaveNodes * 800 / 1e9) + " GB with collisions); these give " + fmt(nodes) + " nodes");
  require(warpSpacing >= warpSection.width, "warp_spacing", warpSpacing,
          "[warp_width = " + fmt(warpSection.width) + ", inf) m: neighbouring warp yarns would overlap");
  require(weftSpacing >= weftSection.width, "weft_spacing", weftSpacing,
          "[weft_width = " + fmt(weftSection.width) + ", inf) m: neighbouring weft yarns would overlap");
  require(warpCrimp < 0 || (std::isfinite(warpCrimp) && warpCrimp < 1), "warp_crimp", warpCrimp,
          "[0, 1), or < 0 for Peirce's touching geometry");
  require(weftCrimp < 0 || (std::isfinite(weftCrimp) && weftCrimp < 1), "weft_crimp", weftCrimp,
          "[0, 1), or < 0 for Peirce's touching geometry");
}

Real WeaveParams::estimatedNodes() const {
  // Each of NW warp yarns crosses NF wefts with cp_per_span CPs per span and about one span past its
  // outer crossings, and the same for the wefts (an upper bound with adaptive resolution).
  const Real NW = Real(ny) * pattern.rows(), NF = Real(nx) * pattern.cols(), n = cpPerSpan;
  return NW * (NF * n + n + 1) + NF * (NW * n + n + 1);
}

namespace {

long floorDiv(long a, long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Height profile of one yarn's centre line, evaluated at node q (q = 0 at the first crossing,
// n CPs per span, nodes equally spaced in projection). Between crossings of different heights the
// line is Peirce's: an arc of radius D/2 about the crossing yarn's centre, the straight segment at
// the weave angle theta, and the mirror arc; between crossings of equal height (a float) it is flat.
// Crossing heights are periodic with the yarn's crossing count.
struct Profile {
  std::vector<Real> zc;  // centre-line height at each crossing [m]
  int n = 1;             // CPs per span
  Real p = 0;            // crossing spacing along the yarn [m]
  Real theta = 0, R = 0; // Peirce weave angle [rad] and arc radius D/2 [m]

  // Height at CP r of n in span k (from crossing k to k + 1; k may run one past either end).
  Real z(long k, long r, long nk) const {
    const long N = static_cast<long>(zc.size());
    const Real z0 = zc[((k % N) + N) % N], z1 = zc[(((k + 1) % N) + N) % N];
    if (r == 0 || z0 == z1) return z0;
    const Real u = p * Real(r) / Real(nk), sg = z1 > z0 ? 1.0 : -1.0;
    const Real ua = R * std::sin(theta);  // projected length of each arc
    if (u <= ua) return z0 + sg * (R - std::sqrt(R * R - u * u));
    if (u >= p - ua) return z1 - sg * (R - std::sqrt(R * R - (p - u) * (p - u)));
    return z0 + sg * (R * (1 - std::cos(theta)) + (u - ua) * std::tan(theta));
  }
  Real s(long k, long r, long nk) const { return p * (0.5 + Real(k * nk + r) / Real(nk)); }  // axial [m]
  // Uniform sampling at n CPs per span, node q = k*n + r.
  Real z(long q) const {
    const long k = floorDiv(q, n);
    return z(k, q - k * n, n);
  }
  Real s(long q) const { return p * (0.5 + Real(q) / Real(n)); }
  // Chain length over `crossings` spans starting at the first crossing [m].
  Real repeatLength(long crossings) const {
    Real L = 0;
    for (long q = 0; q < crossings * n; ++q) L += std::hypot(s(q + 1) - s(q), z(q + 1) - z(q));
    return L;
  }
};

}  // namespace

Weave buildWeave(const WeaveParams& P) {
  P.validate();
  const Pattern& pat = P.pattern;
  const int R = pat.rows(), C = pat.cols();
  const int NW = P.ny * R, NF = P.nx * C;
  const int n = P.cpPerSpan;
  const Real D = P.warpSection.thickness + P.weftSection.thickness;

  // Crimp heights: Peirce's touching geometry splits D equally (h_warp = h_weft = D/2) unless a
  // crimp is given; a given crimp fixes that family's height through Peirce's relations.
  Weave w;
  WeaveSummary& S = w.summary;
  Real hw = 0.5 * D, hf = 0.5 * D;
  if (P.warpCrimp >= 0) hw = peirceFromCrimp(P.weftSpacing, P.warpCrimp, D).h;
  if (P.weftCrimp >= 0) hf = peirceFromCrimp(P.warpSpacing, P.weftCrimp, D).h;
  if (P.warpCrimp >= 0 && P.weftCrimp < 0) hf = std::max(D - hw, 0.0);
  if (P.weftCrimp >= 0 && P.warpCrimp < 0) hw = std::max(D - hf, 0.0);
  if (hw + hf < D * (1 - 1e-12)) {
    const std::string which = P.warpCrimp >= 0 ? "warp_crimp" : "weft_crimp";
    throw ParameterError(which, fmt(P.warpCrimp >= 0 ? P.warpCrimp : P.weftCrimp),
                         "a crimp large enough that h_warp + h_weft >= t_warp + t_weft (yarns would overlap "
                         "at the crossings)");
  }
  S.warpPeirce = peirceFromHeight(P.weftSpacing, hw, D);
  S.weftPeirce = peirceFromHeight(P.warpSpacing, hf, D);

  std::vector<Profile> warp(NW), weft(NF);
  for (int i = 0; i < NW; ++i) {
    warp[i].n = n, warp[i].p = P.weftSpacing, warp[i].theta = S.warpPeirce.theta, warp[i].R = 0.5 * S.warpPeirce.D;
    for (int j = 0; j < NF; ++j) warp[i].zc.push_back(pat.warpOver(i % R, j % C) ? 0.5 * hw : -0.5 * hw);
  }
  for (int j = 0; j < NF; ++j) {
    weft[j].n = n, weft[j].p = P.warpSpacing, weft[j].theta = S.weftPeirce.theta, weft[j].R = 0.5 * S.weftPeirce.D;
    for (int i = 0; i < NW; ++i) weft[j].zc.push_back(pat.warpOver(i % R, j % C) ? -0.5 * hf : 0.5 * hf);
  }

  // CPs in span k of a yarn (k = -1 and crossings - 1: the pieces past its outer crossings).
  const bool adaptive = P.fineRadius >= 0;
  const Real cx = std::isnan(P.fineX) ? 0.5 * NF * P.weftSpacing : P.fineX;
  const Real cy = std::isnan(P.fineY) ? 0.5 * NW * P.warpSpacing : P.fineY;
  Index spans = 0, fineSpans = 0;
  // a, b: the span's ends along the yarn [m]; c: the yarn's other coordinate; (ca, cc): the fine
  // centre in the same (along, across) frame. Fine when the span's nearest point is within fineRadius.
  auto cpIn = [&](Real a, Real b, Real c, Real ca, Real cc) {
    ++spans;
    if (!adaptive || std::hypot(std::clamp(ca, a, b) - ca, c - cc) <= P.fineRadius) return ++fineSpans, n;
    return P.cpCoarse;
  };
  // Each yarn runs (n + 1)/2 CPs of p/n past its outer crossings (half a span when n is even) at any
  // resolution, so its length, mass and series stiffness do not depend on the end spans' CP count;
  // a coarser end span takes its own CPs up to there and one element to the end node, no shorter than
  // p/n (it would lower the critical time step) and shorter than p/n_k + p/n.
  // Returns the nodes and, in `cross`, the node index (from the yarn's first) on each crossing.
  const long m = (n + 1) / 2;
  auto nodesOf = [&](const Profile& pr, long crossings, Real c, Real ca, Real cc, std::vector<Index>& cross,
                     auto place) {
    Vec3Array pts;
    cross.clear();
    auto add = [&](long k, long r, long nk) { pts.push_back(place(pr.s(k, r, nk), pr.z(k, r, nk))); };
    auto cpOf = [&](long k) { return long(cpIn(pr.p * (k + 0.5), pr.p * (k + 1.5), c, ca, cc)); };
    const long n0 = cpOf(-1);
    add(-1, n - m, n);
    for (long r = 1; r < n0; ++r)
      if (r * n >= (n - m + 1) * n0) add(-1, r, n0);
    for (long k = 0; k < crossings - 1; ++k) {
      const long nk = cpOf(k);
      cross.push_back(static_cast<Index>(pts.size()));
      for (long r = 0; r < nk; ++r) add(k, r, nk);
    }
    const long ne = cpOf(crossings - 1);
    cross.push_back(static_cast<Index>(pts.size()));
    for (long r = 0; r * n + ne <= m * ne; ++r) add(crossings - 1, r, ne);
    add(crossings - 1, m, n);
    return pts;
  };
  Fabric& F = w.fabric;
  std::vector<std::vector<Index>> crossW(NW), crossF(NF);  // crossing nodes of each warp / weft yarn
  for (int i = 0; i < NW; ++i) {
    const Real y = (i + 0.5) * P.warpSpacing;
    w.warpYarns.push_back(F.addYarn(nodesOf(warp[i], NF, y, cx, cy, crossW[i], [&](Real s, Real z) { return Vec3(s, y, z); }),
                                    P.warpMaterial, P.warpSection, YarnFamily::Warp));
  }
  for (int j = 0; j < NF; ++j) {
    const Real x = (j + 0.5) * P.weftSpacing;
    w.weftYarns.push_back(F.addYarn(nodesOf(weft[j], NW, x, cy, cx, crossF[j], [&](Real s, Real z) { return Vec3(x, s, z); }),
                                    P.weftMaterial, P.weftSection, YarnFamily::Weft));
  }

  // Summary: crimp and areal density of one repeat (at cpPerSpan CPs per span), clearance at every crossing.
  S.warpYarns = NW, S.weftYarns = NF;
  S.nodes = F.nNodes(), S.elements = F.nElems();
  S.lengthX = NF * P.weftSpacing, S.lengthY = NW * P.warpSpacing;
  S.spans = spans, S.fineSpans = fineSpans;
  S.minElementLength = *std::min_element(F.restLength.begin(), F.restLength.end());
  const Real lw = P.warpMaterial.rho * P.warpMaterial.area, lf = P.weftMaterial.rho * P.weftMaterial.area;
  Real mass = 0, cw = 0, cf = 0;
  for (int i = 0; i < R; ++i) {
    const Real L = warp[i].repeatLength(C);
    mass += lw * L, cw += L / (C * P.weftSpacing) - 1;
  }
  for (int j = 0; j < C; ++j) {
    const Real L = weft[j].repeatLength(R);
    mass += lf * L, cf += L / (R * P.warpSpacing) - 1;
  }
  S.warpCrimpBuilt = cw / R, S.weftCrimpBuilt = cf / C;
  S.arealDensity = mass / (C * P.weftSpacing * R * P.warpSpacing);

  S.requiredGap = 0.5 * D;
  S.minVerticalGap = INFINITY, S.minChainClearance = INFINITY;
  for (int i = 0; i < NW; ++i) {
    const Yarn& yw = F.yarns[w.warpYarns[i]];
    for (int j = 0; j < NF; ++j) {
      const Yarn& yf = F.yarns[w.weftYarns[j]];
      const Index aw = yw.firstNode + crossW[i][j], af = yf.firstNode + crossF[j][i];  // nodes on the crossing
      const bool over = pat.warpOver(i % R, j % C);
      S.minVerticalGap = std::min(S.minVerticalGap, over ? F.pos[aw].z() - F.pos[af].z() : F.pos[af].z() - F.pos[aw].z());
      // 3D distance of the two chains within one span either side of the crossing.
      const Index a0 = j > 0 ? yw.firstNode + crossW[i][j - 1] : yw.firstNode;
      const Index a1 = j + 1 < NF ? yw.firstNode + crossW[i][j + 1] : yw.firstNode + yw.nNodes - 1;
      const Index b0 = i > 0 ? yf.firstNode + crossF[j][i - 1] : yf.firstNode;
      const Index b1 = i + 1 < NW ? yf.firstNode + crossF[j][i + 1] : yf.firstNode + yf.nNodes - 1;
      for (Index a = a0; a < a1; ++a)
        for (Index b = b0; b < b1; ++b)
          S.minChainClearance = std::min(
              S.minChainClearance, closestSegmentSegment(F.pos[a], F.pos[a + 1], F.pos[b], F.pos[b + 1]).distance);
    }
  }
  return w;
}

WeaveParams km2_706() {
  WeaveParams p;
  p.warpSpacing = p.weftSpacing = 25.4e-3 / 34;  // 34 x 34 ends per inch
  YarnMaterial m;
  m.E = 90e9;
  m.rho = 1440;
  m.area = (600.0 / 9000.0 * 1e-3) / m.rho;  // 600 denier = 66.7 tex -> 4.63e-8 m^2 of fibre
  m.failureStrain = 0.05;
  p.warpMaterial = p.weftMaterial = m;
  YarnSection s;
  s.width = 0.65e-3;       // measured 0.6-0.7 mm
  s.thickness = 0.11e-3;   // measured 0.10-0.14 mm; with Peirce: crimp 1.09 %, 180.4 g/m^2
  p.warpSection = p.weftSection = s;
  p.cpPerSpan = 4;
  return p;
}

}  // namespace woven
