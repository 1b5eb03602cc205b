// Yarn breakage (paper Sec. 6.2): an element (CP) is removed when its strain passes the failure
// strain of its yarn. Removal keeps the element's slot (Fabric::alive = 0, K = c = 0, see Fabric.hpp),
// so indices never shift, and releases the element's elastic energy 1/2 K (l - l0)^2 into its own
// book.
//
// The strain compared with the threshold is low-pass filtered in time, per element:
//     eps_f <- eps_f + (1 - exp(-dt/tau)) (eps - eps_f),      tau = L / c,  c = sqrt(E/rho)
// with L = filterLength [m], or, for filterLength < 0, |filterLength| element rest lengths (default
// 4 l0: the spike lasts a few element transit times l0/c, so the filter follows the resolution).
// A step front in a discrete chain overshoots its plateau for a few elements behind the front
// (physics-reference.md: up to ~1.27x; measured 1.04x on Smith's impact at a Courant number of 0.7):
// the raw element strain breaks a yarn whose plateau is below the threshold. The overshoot lives for
// the few element transit times l0/c it takes the front to pass; a strain held for longer than tau
// reaches the threshold with a delay of about tau. A fixed 1 mm filter was enough for 0.2 mm CPs but
// not for 0.75 mm ones (broken at 90 % of the threshold); 4 l0 holds at both. filterLength = 0
// compares the raw element strain (shown against the filtered one in tests/cpp/test_ballistic.cpp and
// docs/ballistic.md).
//
// Optional Weibull distribution of yarn strength: each yarn's failure strain is drawn from a
// Weibull law of modulus m whose mean is the material's failure strain,
//     eps_b = scale * (-ln(1 - U))^(1/m),   scale = mean / Gamma(1 + 1/m),
// with U from a 64-bit Mersenne twister seeded by the user (the same seed, the same strengths).
#pragma once
#include "core/Types.hpp"
#include "fabric/Fabric.hpp"
#include <cstdint>
#include <vector>

namespace woven {

struct BreakageParams {
  bool enabled = false;
  /// Failure strain [-] in (0, 10]; <= 0 here means "each yarn's material failureStrain".
  Real threshold = 0;
  /// Filter length L of tau = L / c: [m] when > 0, |filterLength| element rest lengths when < 0
  /// (default: 4 l0), 0: the raw element strain.
  Real filterLength = -4;
  /// Weibull modulus of the yarn strengths [-]: 0 (all yarns at the threshold) or in [1, 100].
  Real weibullModulus = 0;
  std::uint64_t seed = 1;
  void validate() const;
};

struct BreakEvent {
  long step = 0;          ///< step at whose end the element broke
  Real time = 0;          ///< [s]
  Index yarn = -1, element = -1;
  Vec3 position = Vec3::Zero();  ///< element midpoint [m]
  Real strain = 0;        ///< the filtered strain that passed the threshold [-]
  Real rawStrain = 0;     ///< the element strain at that moment [-]
  Real energy = 0;        ///< elastic energy released [J]
};

/// Everything a run's breakage carries from step to step (for state files, FabricEngine::state):
/// the parameters, the drawn yarn strengths, the filtered strains and the break log.
struct BreakageState {
  BreakageParams params;
  std::vector<Real> strength, filtered;  ///< per yarn, per element (both empty: never configured)
  std::vector<BreakEvent> log;
};

class Breakage {
 public:
  /// Validates, draws the yarn strengths and starts the filter from the fabric's current strains
  /// (Fabric::strain must be up to date).
  void configure(const Fabric& f, const BreakageParams& p);
  const BreakageParams& params() const { return p_; }
  bool enabled() const { return p_.enabled; }

  /// Feeds the strains of the step just made (Fabric::strain at x_{n+1}) to the filter and removes
  /// the elements past their yarn's strength. Returns the elastic energy released [J].
  Real apply(Fabric& f, Real dt, long step, Real time);

  const std::vector<Real>& yarnStrength() const { return strength_; }   ///< [-] per yarn
  const std::vector<Real>& filteredStrain() const { return filtered_; } ///< [-] per element
  const std::vector<BreakEvent>& log() const { return log_; }
  long brokenElements() const { return static_cast<long>(log_.size()); }
  BreakageState state() const { return {p_, strength_, filtered_, log_}; }
  /// Throws ParameterError ("state") unless s fits fabric f: valid parameters, sizes of f, finite
  /// values, logged elements of f that are broken in `alive`.
  static void check(const Fabric& f, const BreakageState& s, const std::vector<std::uint8_t>& alive);
  /// Puts a saved breakage state back (check it first): the filter rates follow from the parameters
  /// as in configure, so a continued run breaks the same elements at the same steps.
  void restore(const Fabric& f, const BreakageState& s);
  /// Yarns with at least one broken element.
  long brokenYarns(const Fabric& f) const;

 private:
  void setRates(const Fabric& f);  // 1/tau per element from p_ (configure, restore)
  BreakageParams p_;
  std::vector<Real> strength_, filtered_, rate_;  // rate_: 1/tau per element [1/s]
  std::vector<BreakEvent> log_;
};

}  // namespace woven
