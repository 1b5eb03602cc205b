#include "fabric/Material.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

// Physical ranges, not just signs: a positive but absurd value (rho = 1e-300, area = 1e300) passes a
// sign check and turns into infinite stiffness, NaN damping or NaN velocities at the first step. The
// ranges hold every fibre and yarn woven is meant for with decades to spare (README, Parameters).
void YarnMaterial::validate(const std::string& p) const {
  require(std::isfinite(E) && E >= 1e5 && E <= 1e13, p + "E", E, "[1e5, 1e13] Pa");
  require(std::isfinite(rho) && rho >= 1 && rho <= 1e5, p + "rho", rho, "[1, 1e5] kg/m^3");
  require(std::isfinite(area) && area >= 1e-16 && area <= 1e-2, p + "area", area, "[1e-16, 1e-2] m^2");
  require(std::isfinite(dampingRatio) && dampingRatio >= 0 && dampingRatio < 10, p + "damping", dampingRatio,
          "[0, 10) (damping ratio of the highest chain mode)");
  require(std::isfinite(failureStrain) && failureStrain > 0 && failureStrain <= 10, p + "failure_strain",
          failureStrain, "(0, 10]");
  require(std::isfinite(bending) && bending >= 0 && bending <= 1, p + "bending", bending,
          "[0, 1] N m^2 (the yarn's bending stiffness EI; 0: none)");
}

void YarnSection::validate(const std::string& p) const {
  require(std::isfinite(width) && width >= 1e-8 && width <= 1, p + "width", width, "[1e-8, 1] m");
  require(std::isfinite(thickness) && thickness >= 1e-8 && thickness <= 1, p + "thickness", thickness,
          "[1e-8, 1] m");
}

}  // namespace woven
