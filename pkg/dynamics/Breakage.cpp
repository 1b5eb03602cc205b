#include "dynamics/Breakage.hpp"
#include "core/Errors.hpp"
#include "core/Parallel.hpp"
#include <algorithm>
#include <cmath>
#include <random>

namespace woven {

void BreakageParams::validate() const {
  require(std::isfinite(threshold) && threshold <= 10 && !(threshold > 0 && threshold < 1e-12), "break_strain", threshold,
          "[1e-12, 10] (<= 0: the material's failure strain)");
  require(std::isfinite(filterLength) && filterLength >= -100 && filterLength <= 1, "break_filter", filterLength,
          "[-100, 1]: > 0 a length [m], < 0 that many element lengths, 0 the raw strain");
  require(weibullModulus == 0 || (weibullModulus >= 1 && weibullModulus <= 100), "weibull_m", weibullModulus,
          "0 (no scatter) or [1, 100]");
}

void Breakage::configure(const Fabric& f, const BreakageParams& p) {
  p.validate();
  p_ = p;
  log_.clear();
  strength_.assign(f.yarns.size(), 0);
  std::mt19937_64 rng(p.seed);
  for (std::size_t y = 0; y < f.yarns.size(); ++y) {
    const Real mean = p.threshold > 0 ? p.threshold : f.materials[f.yarns[y].material].failureStrain;
    Real s = mean;
    if (p.weibullModulus > 0) {
      // U in [0, 1) from the top 53 bits: the same on every platform (std distributions are not).
      const Real U = static_cast<Real>(rng() >> 11) * 0x1.0p-53;
      const Real scale = mean / std::tgamma(1 + 1 / p.weibullModulus);
      s = scale * std::pow(-std::log1p(-U), 1 / p.weibullModulus);
    }
    strength_[y] = s;
  }
  filtered_ = f.strain;
  setRates(f);
}

void Breakage::setRates(const Fabric& f) {
  rate_.assign(f.nElems(), 0);
  if (strength_.empty()) return;
  for (Index e = 0; e < f.nElems(); ++e) {
    const YarnMaterial& m = f.materials[f.yarns[f.elemYarn[e]].material];
    const Real L = p_.filterLength > 0 ? p_.filterLength : -p_.filterLength * f.restLength[e];
    rate_[e] = L > 0 ? std::sqrt(m.E / m.rho) / L : INFINITY;
  }
}

void Breakage::check(const Fabric& f, const BreakageState& s, const std::vector<std::uint8_t>& alive) {
  const std::string why = "a breakage state of this fabric: ";
  try {
    s.params.validate();
  } catch (const ParameterError& e) {
    throw ParameterError("state", "breakage parameters", why + e.what());
  }
  const bool none = s.strength.empty() && s.filtered.empty();
  if (!none && (s.strength.size() != f.yarns.size() || s.filtered.size() != static_cast<std::size_t>(f.nElems())))
    throw ParameterError("state", fmt(s.strength.size()) + " strengths and " + fmt(s.filtered.size()) + " filtered strains",
                         why + fmt(f.yarns.size()) + " and " + fmt(f.nElems()));
  if (none && (s.params.enabled || !s.log.empty()))
    throw ParameterError("state", "breakage on without strengths", why + "strengths and filtered strains when enabled");
  for (Real v : s.strength)
    if (!(std::isfinite(v) && v > 0)) throw ParameterError("state", "yarn strength " + fmt(v), why + "(0, inf) finite strengths");
  for (Real v : s.filtered)
    if (!std::isfinite(v)) throw ParameterError("state", "filtered strain " + fmt(v), why + "finite filtered strains");
  if (s.log.size() > static_cast<std::size_t>(f.nElems()))
    throw ParameterError("state", fmt(s.log.size()) + " breaks", why + "at most one break per element");
  for (const BreakEvent& ev : s.log) {
    const bool ok = ev.element >= 0 && ev.element < f.nElems() && ev.yarn == f.elemYarn[ev.element] &&
                    alive.size() == static_cast<std::size_t>(f.nElems()) && !alive[ev.element] && ev.step >= 0 &&
                    std::isfinite(ev.time) && ev.position.allFinite() && std::isfinite(ev.strain) &&
                    std::isfinite(ev.rawStrain) && std::isfinite(ev.energy) && ev.energy >= 0;
    if (!ok) throw ParameterError("state", "break of element " + fmt(ev.element), why + "breaks of broken elements of this fabric, finite values");
  }
}

void Breakage::restore(const Fabric& f, const BreakageState& s) {
  p_ = s.params;
  strength_ = s.strength;
  filtered_ = s.filtered;
  log_ = s.log;
  setRates(f);
}

Real Breakage::apply(Fabric& f, Real dt, long step, Real time) {
  if (!p_.enabled) return 0;
  Real released = 0;
  // The filter of each element on its own (threads), then the breaks in element order.
  parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) {
    // Exact first-order low-pass over the step (exp: stable for any dt/tau; tau = 0 gives eps).
    if (f.alive[e]) filtered_[e] += (1 - std::exp(-dt * rate_[e])) * (f.strain[e] - filtered_[e]);
  });
  for (Index e = 0, n = f.nElems(); e < n; ++e) {
    if (!f.alive[e]) continue;
    const Real eps = f.strain[e];
    const Index y = f.elemYarn[e];
    if (!(filtered_[e] > strength_[y])) continue;
    const Index a = f.elem0[e];
    const Real stretch = (f.pos[a + 1] - f.pos[a]).norm() - f.restLength[e];
    BreakEvent ev;
    ev.step = step, ev.time = time, ev.yarn = y, ev.element = e;
    ev.position = 0.5 * (f.pos[a] + f.pos[a + 1]);
    ev.strain = filtered_[e], ev.rawStrain = eps;
    ev.energy = stretch > 0 ? 0.5 * f.stiffness[e] * stretch * stretch : 0.0;
    released += ev.energy;
    log_.push_back(ev);
    f.alive[e] = 0;
    f.stiffness[e] = 0;
    f.damping[e] = 0;
  }
  return released;
}

long Breakage::brokenYarns(const Fabric& f) const {
  std::vector<std::uint8_t> hit(f.yarns.size(), 0);
  for (const BreakEvent& ev : log_) hit[ev.yarn] = 1;
  return static_cast<long>(std::count(hit.begin(), hit.end(), 1));
}

}  // namespace woven
