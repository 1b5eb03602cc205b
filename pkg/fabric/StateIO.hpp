// Binary save/load of a fabric's state, bit for bit: positions, velocities, cross-sections, clock,
// broken elements, breakage state (strengths, strain filter, break log) and energy books, so that a
// run continued from a file matches the run that wrote it, breakage included.
//
// Format "WOVENST3" (little-endian as in memory), version 4 (version 3 is read too: its friction book is 0):
//   magic[8] u32 version u32 0 u64 topology-fingerprint i64 nodes i64 elements i64 yarns
//   i64 step f64 time f64 last_dt
//   nodes x (3 f64 position) nodes x (3 f64 velocity) nodes x f64 section eps nodes x (3 f64 section dir)
//   elements x u8 alive, elements x f64 stiffness, elements x f64 damping
//   u8 books_started u8 spring_seen 11 x f64 books (kinetic elastic damped work body_work contact
//       contact_input spring released initial projection), f64 friction (version 4 only)
//   u8 breakage_enabled f64 threshold f64 filter_length f64 weibull_m u64 seed
//   i64 n_strength, n_strength x f64; i64 n_filtered, n_filtered x f64
//   i64 n_breaks, n_breaks x (i64 step f64 time i32 yarn i32 element 3 f64 position f64 strain
//       f64 raw_strain f64 energy)
//   u64 checksum: FNV-1a 64 of every byte before it
// Nothing may follow the checksum. The fingerprint (topologyFingerprint) ties a file to the weave that
// wrote it: a file of another weave with the same node count is refused. Older formats (WOVENST1/2,
// without books, breakage or checksum) are refused with a message saying so.
//
// Writes are atomic: the bytes go to a temporary file in the target's folder, are flushed, checked,
// fsync'ed and renamed over the target, so a failed or killed write leaves the previous file whole.
#pragma once
#include "core/Types.hpp"
#include "dynamics/Breakage.hpp"
#include "dynamics/Energy.hpp"
#include <cstdint>
#include <string>

namespace woven {

struct Fabric;

struct KinematicState {
  Vec3Array pos, vel;      ///< [m], [m/s]
  std::vector<Real> flat;  ///< section deformation eps per node [-]
  Vec3Array dir;           ///< section minor-axis direction per node [-]
  long step = 0;
  Real time = 0;           ///< [s]
  Real lastDt = 0;         ///< dt of the step that produced this state [s]
  std::uint64_t topology = 0;  ///< topologyFingerprint of the fabric the state belongs to
  long yarns = 0;              ///< yarns of that fabric
  std::vector<std::uint8_t> alive;       ///< per element
  std::vector<Real> stiffness, damping;  ///< per element [N/m], [N s/m] (0 where broken)
  bool booksStarted = false, springSeen = false;  ///< ChainDynamics: books computed; contact springs booked
  EnergyBooks books;       ///< [J]
  BreakageState breakage;
  /// The collision stage's memory (CollisionStage::memory: persistent crossings, pairs' measure
  /// memory, the last body contacts), opaque bytes; empty: none (collisions off, a last good state,
  /// or a file of version 4 or earlier, whose run then continues as one that forgot it).
  std::string contacts;
};

/// 64-bit fingerprint of what a state file must match: counts, yarns (nodes, elements, family,
/// section) and the bits of every rest length, node mass and section radius (so the geometry, the
/// density and the area; not E or the damping, which a loaded state takes from the engine).
std::uint64_t topologyFingerprint(const Fabric& f);

/// Atomic write (see above). Throws ParameterError ("path") for a path with a NUL character, and
/// std::runtime_error naming the path and the system's reason when the write fails.
void saveState(const std::string& path, const KinematicState& s);
/// Reads and checks a state file: format, version, sizes, checksum, no trailing bytes, finite and
/// in-range values (step >= 0, time and last_dt finite and >= 0, eps in [0, 1), unit section
/// directions, alive 0/1, broken elements with zero stiffness). Throws ParameterError ("path" for a
/// bad path or unreadable file, "state" for bad contents, naming what is wrong); expectNodes >= 0
/// also requires that node count. Checks against a fabric are FabricEngine::setState's.
KinematicState loadState(const std::string& path, long expectNodes = -1);

/// Writes `bytes` to `path` atomically (temporary in the same folder, flush, check, fsync, rename);
/// a target that exists and is not a regular file (a device such as /dev/null, a pipe) is written
/// in place, with the same checks. Throws as saveState. Used for every file woven writes.
void writeFileAtomic(const std::string& path, const std::string& bytes);

}  // namespace woven
