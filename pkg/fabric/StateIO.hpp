// Binary save/load of a fabric's state (positions, velocities, cross-sections, time, step), bit
// for bit. Format "WOVENST2": int64 nodes, int64 step, double time, double last dt, then nodes*3 doubles of
// positions, nodes*3 of velocities, nodes of section deformations eps, nodes*3 of section minor-axis
// directions, little-endian as in memory. "WOVENST1" files (no sections) still load.
#pragma once
#include "core/Types.hpp"
#include <string>

namespace woven {

struct KinematicState {
  Vec3Array pos, vel;  ///< [m], [m/s]
  std::vector<Real> flat;  ///< section deformation eps per node [-] (empty: sections not stored)
  Vec3Array dir;           ///< section minor-axis direction per node [-] (empty with flat)
  long step = 0;
  Real time = 0;       ///< [s]
  Real lastDt = 0;     ///< dt of the step that produced this state [s] (0 in WOVENST1 files)
};

void saveState(const std::string& path, const KinematicState& s);
/// Throws std::runtime_error if the file is missing or malformed, ParameterError ("state") if its
/// node count differs from expectNodes (when expectNodes >= 0).
KinematicState loadState(const std::string& path, long expectNodes = -1);

}  // namespace woven
