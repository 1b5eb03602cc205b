#include "law/ContactParams.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

void ContactParams::validate() const {
  require(std::isfinite(restitution) && restitution >= 0 && restitution <= 1, "restitution", restitution, "[0, 1]");
  require(std::isfinite(friction) && friction >= 0, "friction", friction, "[0, inf) (Coulomb coefficient)");
  require(std::isfinite(mcd) && mcd > 0 && mcd < 1, "mcd", mcd, "(0, 1) (maximum cross-sectional deformation)");
  require(std::isfinite(margin) && margin >= 0, "margin", margin, "[0, inf) m");
  require(std::isfinite(skin) && skin >= 0, "skin", skin, "[0, inf) m");
  require(std::isfinite(tolerance) && tolerance > 0, "tolerance", tolerance, "(0, inf) m/s");
  require(maxIterations >= 1, "max_iterations", maxIterations, "[1, inf)");
  require(flattenPasses >= 1, "flatten_passes", flattenPasses, "[1, inf)");
  require(std::isfinite(positionCorrection) && positionCorrection >= 0 && positionCorrection <= 1,
          "position_correction", positionCorrection, "[0, 1]");
  require(std::isfinite(correctionSlop) && correctionSlop >= 0, "correction_slop", correctionSlop, "[0, inf) m");
  require(std::isfinite(cacheDistance) && cacheDistance >= 0, "contact_cache", cacheDistance, "[0, inf) m (0: off)");
  require(threads >= 0 && threads <= 64, "threads", threads, "[0, 64] (0: OpenMP's count)");
  require(selfExclude >= 1, "self_exclude", selfExclude, "[1, inf) elements (1: CPs sharing a node)");
}

}  // namespace woven
