// Snapshot of a whole FabricEngine in memory: the fabric as built (nodes, elements, yarns, materials),
// its loads, limits, collision settings, spring substeps and rigid bodies, and its state (positions, velocities,
// sections, clock, broken elements, breakage state, energy books: StateIO's KinematicState), so that
// an engine rebuilt from the bytes continues bit for bit as the one that wrote them. The YADE plugin
// (pkg/yade/, docs/yade_native.md) stores it in O.save's files.
//
// Like saveState, taking a snapshot forgets the collision stage's carried contacts (both runs then
// test every pair at their next step). Not kept: the collision statistics and timers, the last good
// state (the restored state is the last good one), and flattening=springs' rest sections.
//
// Format "WOVENSN4", little-endian as in memory, ending with an FNV-1a 64 checksum of the bytes before
// it; restoreSnapshot refuses a truncated, altered or foreign blob (ParameterError "snapshot") and
// checks the state as FabricEngine::setState does.
#pragma once
#include "engine/FabricEngine.hpp"
#include <memory>
#include <string>

namespace woven {

/// The bytes of `e` (see above). Forgets the carried contacts of `e`.
std::string engineSnapshot(FabricEngine& e);
/// A new engine equal to the one that wrote `bytes`.
std::shared_ptr<FabricEngine> restoreSnapshot(const std::string& bytes);

}  // namespace woven
