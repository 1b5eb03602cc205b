// Peirce's plain-weave geometry (Peirce 1937; physics-reference.md). For one yarn family:
//   p = (l - D*theta)*cos(theta) + D*sin(theta)         (projected spacing of the crossing yarns)
//   h = (l - D*theta)*sin(theta) + D*(1 - cos(theta))   (crimp height, peak-to-trough centre line)
//   c = (l - p)/p                                        (crimp)
// where l is the yarn length between crossings, theta the weave angle and D = d1 + d2 the sum of
// the two yarns' thicknesses (h1 + h2 = D when the yarns touch). All lengths in metres.
#pragma once
#include "core/Types.hpp"

namespace woven {

struct PeirceState {
  Real p = 0;      ///< projected spacing of the crossing yarns [m]
  Real h = 0;      ///< crimp height [m]
  Real D = 0;      ///< D = d1 + d2 [m]
  Real theta = 0;  ///< weave angle [rad]
  Real l = 0;      ///< yarn length between crossings [m]
  Real crimp() const { return (l - p) / p; }
};

/// theta and l from spacing p, crimp height h and D (bisection on the monotonic h(theta)).
/// Throws ParameterError if h is not reachable (h < 0 or straight part would be negative).
PeirceState peirceFromHeight(Real p, Real h, Real D);
/// theta, l and h from spacing p, crimp c and D (bisection on the monotonic p(theta)).
PeirceState peirceFromCrimp(Real p, Real crimp, Real D);

}  // namespace woven
