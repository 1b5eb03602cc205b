// Oriented bounding box (paper Sec. 4.1.1): centre C, right-handed orthonormal axes A0, A1, A2
// (columns of `axes`), half-extents e0, e1, e2. The solid box is {C + sum x_i A_i : |x_i| <= e_i}.
#pragma once
#include "core/Types.hpp"
#include <Eigen/Dense>

namespace woven {

using Mat3 = Eigen::Matrix<Real, 3, 3>;

struct OBB {
  Vec3 centre = Vec3::Zero();      ///< [m]
  Mat3 axes = Mat3::Identity();    ///< columns A0, A1, A2, orthonormal, right-handed
  Vec3 extent = Vec3::Zero();      ///< half-extents e0, e1, e2 [m]

  Vec3 axis(int i) const { return axes.col(i); }
  /// Vertex for signs s_i in {-1, +1}: C + sum s_i e_i A_i.
  Vec3 vertex(int s0, int s1, int s2) const {
    return centre + axes * Vec3(s0 * extent[0], s1 * extent[1], s2 * extent[2]);
  }
  /// Signed distance-like test: max over axes of |local coordinate| - extent (<= 0 inside).
  Real outside(const Vec3& p) const { return ((axes.transpose() * (p - centre)).cwiseAbs() - extent).maxCoeff(); }
};

}  // namespace woven
