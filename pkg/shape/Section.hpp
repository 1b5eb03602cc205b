// The CP's shape: an elliptic cylinder between its two nodes, whose cross-section at each node starts
// circular (radius r0) and flattens into an ellipse when yarns press on each other (paper Sec. 5.2.2,
// Fig. 9). The deformation eps = 1 - b/r0 of a node (b: the minor semi-axis, along Fabric::secDir)
// grows until the maximum cross-sectional deformation (MCD); past it the section is locked.
#pragma once
#include "core/Types.hpp"
#include <string>

namespace woven {

enum class SectionRule : std::uint8_t {
  /// The paper's rule: a = r0 (1 + eps), b = r0 (1 - eps) (the area shrinks by 1 - eps^2).
  Paper = 0,
  /// Constant area (the paper's stated assumption): a = r0 / (1 - eps), b = r0 (1 - eps).
  ConstantArea = 1,
};

/// "paper" or "constant_area"; throws ParameterError("section_rule") otherwise.
SectionRule sectionRuleByName(const std::string& name);
const char* sectionRuleName(SectionRule r);

/// Semi-axes of a section: a (major, across the contact normal) and b (minor, along it) [m].
struct SemiAxes {
  Real a, b;
};

/// Semi-axes for natural radius r0 [m] and deformation eps in [0, 1).
inline SemiAxes semiAxes(Real r0, Real eps, SectionRule rule) {
  const Real b = r0 * (1 - eps);
  return {rule == SectionRule::Paper ? r0 * (1 + eps) : r0 / (1 - eps), b};
}

/// Support of an ellipse with semi-axes (a along u, b along d) in direction w: max over the ellipse
/// of (p - centre).w = sqrt(a^2 (u.w)^2 + b^2 (d.w)^2) [m].
inline Real ellipseSupport(const Vec3& u, const Vec3& d, Real a, Real b, const Vec3& w) {
  const Real pu = a * u.dot(w), pd = b * d.dot(w);
  return std::sqrt(pu * pu + pd * pd);
}

}  // namespace woven
