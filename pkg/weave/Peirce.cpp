#include "weave/Peirce.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

namespace {
// Bisection to machine precision on a monotonic function g with g(lo), g(hi) of opposite signs.
template <class G>
Real bisect(G g, Real lo, Real hi) {
  Real glo = g(lo);
  for (int it = 0; it < 200; ++it) {
    const Real mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    const Real gm = g(mid);
    if ((gm < 0) == (glo < 0)) lo = mid, glo = gm;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}
}  // namespace

// Arguments are named as the Python functions name them (p, h, D, crimp); finite physical ranges,
// so that no NaN or infinity comes out.
PeirceState peirceFromHeight(Real p, Real h, Real D) {
  require(std::isfinite(p) && p >= 1e-8 && p <= 1, "p", p, "[1e-8, 1] m (yarn spacing)");
  require(std::isfinite(D) && D >= 1e-8 && D <= 1, "D", D, "[1e-8, 1] m (sum of crossing yarn thicknesses)");
  require(std::isfinite(h), "h", h, "finite [m] (crimp height)");
  PeirceState s;
  s.p = p, s.h = h, s.D = D;
  // Eliminating l: h(theta) = (p - D sin t) tan t + D (1 - cos t), increasing while p > D sin t
  // (dh/dtheta = (p - D sin t)/cos^2 t).
  const Real tmax = (p >= D) ? 0.5 * M_PI * (1 - 1e-12) : std::asin(p / D);
  auto hOf = [&](Real t) { return (p - D * std::sin(t)) * std::tan(t) + D * (1 - std::cos(t)); };
  const Real hmax = hOf(tmax);
  require(h >= 0 && h < hmax, "h", h, "[0, " + fmt(hmax) + ") m for this spacing and thickness");
  s.theta = h == 0 ? 0 : bisect([&](Real t) { return hOf(t) - h; }, 0.0, tmax);
  s.l = D * s.theta + (p - D * std::sin(s.theta)) / std::cos(s.theta);
  return s;
}

PeirceState peirceFromCrimp(Real p, Real crimp, Real D) {
  require(std::isfinite(p) && p >= 1e-8 && p <= 1, "p", p, "[1e-8, 1] m (yarn spacing)");
  require(std::isfinite(D) && D >= 1e-8 && D <= 1, "D", D, "[1e-8, 1] m (sum of crossing yarn thicknesses)");
  require(std::isfinite(crimp) && crimp >= 0 && crimp < 1, "crimp", crimp, "[0, 1)");
  PeirceState s;
  s.p = p, s.D = D;
  s.l = p * (1 + crimp);
  // p(theta) = (l - D t) cos t + D sin t decreases while l > D t (dp/dt = -(l - D t) sin t).
  const Real tmax = std::min(0.5 * M_PI, s.l / D);
  auto pOf = [&](Real t) { return (s.l - D * t) * std::cos(t) + D * std::sin(t); };
  require(pOf(tmax) <= p, "crimp", crimp, "a crimp reachable with straight segments of length >= 0");
  s.theta = crimp == 0 ? 0 : bisect([&](Real t) { return pOf(t) - p; }, 0.0, tmax);
  s.h = (s.l - D * s.theta) * std::sin(s.theta) + D * (1 - std::cos(s.theta));
  return s;
}

}  // namespace woven
