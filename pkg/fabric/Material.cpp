#include "fabric/Material.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

void YarnMaterial::validate(const std::string& p) const {
  require(std::isfinite(E) && E > 0, p + "E", E, "(0, inf) Pa");
  require(std::isfinite(rho) && rho > 0, p + "rho", rho, "(0, inf) kg/m^3");
  require(std::isfinite(area) && area > 0, p + "area", area, "(0, inf) m^2");
  require(std::isfinite(dampingRatio) && dampingRatio >= 0 && dampingRatio < 10, p + "damping", dampingRatio,
          "[0, 10) (damping ratio of the highest chain mode)");
  require(std::isfinite(failureStrain) && failureStrain > 0, p + "failure_strain", failureStrain, "(0, inf)");
}

void YarnSection::validate(const std::string& p) const {
  require(std::isfinite(width) && width > 0, p + "width", width, "(0, inf) m");
  require(std::isfinite(thickness) && thickness > 0, p + "thickness", thickness, "(0, inf) m");
}

}  // namespace woven
