// Loads on the fabric: kinematic nodes (fixed or driven at a prescribed velocity), point forces and a
// body acceleration. Kept as short lists: only a few nodes are loaded, the loop over them is cheap.
#pragma once
#include "core/Types.hpp"
#include <vector>

namespace woven {

struct Loads {
  Vec3 bodyAcceleration = Vec3::Zero();  ///< e.g. gravity [m/s^2], acts on every free node

  std::vector<Index> kinematicNodes;     ///< nodes whose velocity is prescribed (fixed: zero)
  Vec3Array kinematicVelocity;           ///< their velocity [m/s]
  Real velocityRamp = 0;                 ///< prescribed velocities grow linearly from 0 over this time [s] (0: at once)
  Vec3Array reaction;                    ///< force the support exerts on each such node [N]

  std::vector<Index> forceNodes;         ///< nodes with a constant external point force
  Vec3Array forceValues;                 ///< [N]
};

}  // namespace woven
