// Basic numeric types shared by every room of woven. SI units everywhere.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace woven {

using Real = double;                       ///< all physics in double precision
using Vec3 = Eigen::Matrix<Real, 3, 1>;    ///< same type as YADE's Vector3r (yade-double)
using Vec3Array = std::vector<Vec3>;       ///< structure-of-arrays column of 3-vectors
using Index = std::int32_t;                ///< node / element / yarn index

}  // namespace woven
