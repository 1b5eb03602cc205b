// Helpers shared by the chain-dynamics tests: straight chains built with Fabric::addYarn, a catcher
// for ParameterError's parameter name, and seeded random velocity fields.
#pragma once
#include "core/Errors.hpp"
#include "fabric/Fabric.hpp"
#include <functional>
#include <random>
#include <string>

namespace woven_test {

// Debug/sanitizer builds (-O0, Eigen's asserts, ASan+UBSan) run the step loop ~300x slower than
// Release. There the long runs are shortened (same code paths, so memory and UB errors are still
// found); the physics tolerances are met at full length in Release, where the shortened runs would
// pass too (they are checked against the same theory, not the same numbers).
#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
inline constexpr bool kSlowBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(undefined_behavior_sanitizer)
inline constexpr bool kSlowBuild = true;
#else
inline constexpr bool kSlowBuild = false;
#endif
#else
inline constexpr bool kSlowBuild = false;
#endif

/// n in Release, n/slowDivisor in Debug/sanitizer builds.
inline long runLength(long n, long slowDivisor) { return kSlowBuild ? n / slowDivisor : n; }

using woven::Fabric;
using woven::Index;
using woven::Real;
using woven::Vec3;
using woven::Vec3Array;
using woven::YarnMaterial;
using woven::YarnSection;

/// KM2 yarn material (E 90 GPa, rho 1440 kg/m^3, A 4.63e-8 m^2) with the given options.
inline YarnMaterial km2Material(Real dampingRatio = 0.0, bool tensionOnly = true) {
  YarnMaterial m;
  m.E = 90e9;
  m.rho = 1440;
  m.area = (600.0 / 9000.0 * 1e-3) / m.rho;
  m.dampingRatio = dampingRatio;
  m.tensionOnly = tensionOnly;
  return m;
}

/// One straight yarn of `elements` CPs of length l0 along x, starting at the origin.
inline Fabric straightChain(int elements, Real l0, const YarnMaterial& m = km2Material()) {
  Vec3Array pts;
  for (int i = 0; i <= elements; ++i) pts.push_back(Vec3(i * l0, 0, 0));
  Fabric f;
  f.addYarn(pts, m, YarnSection());
  return f;
}

/// Sets every node velocity to a seeded Gaussian field with standard deviation `sigma` [m/s]
/// along the axes flagged in `axes` (e.g. (1, 0, 0): axial only).
inline void randomVelocities(Fabric& f, unsigned seed, Real sigma, const Vec3& axes = Vec3(1, 1, 1)) {
  std::mt19937 rng(seed);
  std::normal_distribution<Real> g(0.0, sigma);
  for (Vec3& v : f.vel) {
    const Real a = g(rng), b = g(rng), c = g(rng);
    v = Vec3(a, b, c).cwiseProduct(axes);
  }
}

/// Runs f, returns the parameter() of the ParameterError it throws ("" if none).
inline std::string parameterOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const woven::ParameterError& e) {
    return e.parameter();
  }
  return "";
}

inline Real rel(Real a, Real b) { return std::abs(a - b) / std::abs(b); }

}  // namespace woven_test
