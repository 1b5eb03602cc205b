// Builds a Fabric from a weave: pattern repeat, spacing, sections, crimp (given or from Peirce),
// C1 B-spline centre lines with CP nodes, replicated nx x ny with continuous yarns.
//
// Frame: warp yarns run along x, spaced warpSpacing apart in y; weft yarns run along y, spaced
// weftSpacing apart in x; z is normal to the fabric. Crossing (i, j) sits at
// x = (j + 1/2)*weftSpacing, y = (i + 1/2)*warpSpacing; the yarn on top there has its centre line at
// +h/2, the other at -h/2 (its own crimp height h), so the centre-line gap is (h_warp + h_weft)/2,
// which Peirce's touching condition makes (t_warp + t_weft)/2.
//
// Centre line (Figure 2b/2c): the zigzag through the crossings is smoothed into Peirce's shape
// (arcs of radius D/2 about the crossing yarn, straight segments at the weave angle; flat along
// floats). Arcs and lines joined with common tangents are exactly a C1 rational quadratic B-spline,
// so this is the paper's B-spline smoothing with its control polygon fixed by Peirce's geometry
// rather than by a free smoothing parameter. It is sampled by CP nodes equally spaced in projection
// with a node on every crossing (the cpPerSpan - 1 "extra nodes" between crossings). The node on a crossing sits exactly at +-h/2, so the
// centre-line gap there is exactly (t_warp + t_weft)/2; the straight CPs next to it cut inside the
// arc, so the 3D distance of the two node chains is slightly smaller (reported as
// minChainClearance; it tends to the gap as cpPerSpan grows).
//
// Adaptive resolution (fineRadius >= 0): a span whose nearest point lies within fineRadius of the
// fine centre gets cpPerSpan CPs, every other span cpCoarse. A node stays on every crossing, so the
// crossings keep their gap and the weave its over/under order; coarser than one CP per span is not
// offered, because a chord over a skipped crossing runs through the crossing yarn's centre line. The
// chains need nothing special at a seam: Fabric::addYarn lumps each node's mass from its actual
// neighbouring elements (rho*A*l/2 each side) and gives each element K = E*A/l0, so a yarn's mass and
// series stiffness are rho*A and E*A over its chain length at any mix of resolutions.
#pragma once
#include "core/Types.hpp"
#include "fabric/Fabric.hpp"
#include "weave/Pattern.hpp"
#include "weave/Peirce.hpp"
#include <cmath>

namespace woven {

struct WeaveParams {
  Pattern pattern = Pattern::plain();
  int nx = 1;                  ///< repeats along x (weft yarns = nx * pattern.cols) [-]
  int ny = 1;                  ///< repeats along y (warp yarns = ny * pattern.rows) [-]
  Real warpSpacing = 25.4e-3 / 34;  ///< centre distance of neighbouring warp yarns [m]
  Real weftSpacing = 25.4e-3 / 34;  ///< centre distance of neighbouring weft yarns [m]
  YarnSection warpSection, weftSection;
  YarnMaterial warpMaterial, weftMaterial;
  Real warpCrimp = -1;         ///< < 0: from Peirce with touching yarns; else given [-]
  Real weftCrimp = -1;
  int cpPerSpan = 4;           ///< CPs between neighbouring crossings (>= 1); inside fineRadius if adaptive
  Real fineRadius = -1;        ///< [m] adaptive resolution within this distance of the fine centre; < 0: uniform
  int cpCoarse = 1;            ///< CPs per span outside fineRadius, [1, cpPerSpan] (used if fineRadius >= 0)
  Real fineX = NAN, fineY = NAN;  ///< fine centre [m] in the fabric's frame; NaN: the middle of the fabric

  void validate() const;       ///< throws ParameterError naming the parameter and range
  /// Nodes the weave will have (an upper bound with adaptive resolution), for the size check.
  Real estimatedNodes() const;
};

/// Largest weave buildWeave accepts [nodes]: about 800 bytes per node with collisions on (arrays of
/// the nodes and CPs, bounds, pairs, caches), so 4 GB (README, Parameters).
inline constexpr Real kMaxWeaveNodes = 5e6;

struct WeaveSummary {
  int warpYarns = 0, weftYarns = 0;
  Index nodes = 0, elements = 0;
  PeirceState warpPeirce, weftPeirce;  ///< Peirce geometry of each family (crimp heights used)
  Real warpCrimpBuilt = 0, weftCrimpBuilt = 0;  ///< (chain length - projected)/projected over a repeat
  Real arealDensity = 0;       ///< from the built chains over one repeat [kg/m^2]
  Real requiredGap = 0;        ///< (t_warp + t_weft)/2 [m]
  Real minVerticalGap = 0;     ///< min over crossings of the centre-line gap at the crossing [m]
  Real minChainClearance = 0;  ///< min over crossings of the 3D distance of the two node chains [m]
  Real lengthX = 0, lengthY = 0;  ///< nominal fabric size nx*cols*weftSpacing, ny*rows*warpSpacing [m]
  Index spans = 0, fineSpans = 0;  ///< spans between crossings (and yarn ends), and those at cpPerSpan CPs
  Real minElementLength = 0;   ///< shortest element [m]: it sets the critical time step
};

struct Weave {
  Fabric fabric;
  WeaveSummary summary;
  std::vector<Index> warpYarns, weftYarns;  ///< yarn indices in the fabric
};

Weave buildWeave(const WeaveParams& params);

/// KM2 style 706 (600 denier para-aramid, 34 x 34 ends/inch, rho 1440, E 90 GPa, 5 % failure).
WeaveParams km2_706();

}  // namespace woven
