// Binary save/load of a fabric's kinematic state (positions, velocities, time, step), bit for bit.
// Format: "WOVENST1", int64 nodes, int64 step, double time, then nodes*3 doubles of positions and
// nodes*3 doubles of velocities, little-endian as in memory.
#pragma once
#include "core/Types.hpp"
#include <string>

namespace woven {

struct KinematicState {
  Vec3Array pos, vel;  ///< [m], [m/s]
  long step = 0;
  Real time = 0;       ///< [s]
};

void saveState(const std::string& path, const KinematicState& s);
/// Throws std::runtime_error if the file is missing or malformed, ParameterError ("state") if its
/// node count differs from expectNodes (when expectNodes >= 0).
KinematicState loadState(const std::string& path, long expectNodes = -1);

}  // namespace woven
