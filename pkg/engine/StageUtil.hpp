// Small helpers shared by the collision stage's files (engine/CollisionStage.cpp and engine/Stage*.cpp):
// the phase clock, a CP locked at the MCD, a maximum taken as a sum, a body contact's key.
#pragma once
#include "fabric/Fabric.hpp"
#include <algorithm>
#include <chrono>
#include <cstdint>

namespace woven {
namespace stage {
using Clock = std::chrono::steady_clock;
inline double since(Clock::time_point& t) {
  const auto now = Clock::now();
  const double s = std::chrono::duration<double>(now - t).count();
  t = now;
  return s;
}
// Both end sections at the MCD: the CP's flattening capacity is 0 along any normal (its reach at the
// MCD is its reach now), so the capacity need not be computed.
inline bool lockedCP(const Fabric& f, Index e, Real mcd) {
  return f.secFlat[f.elem0[e]] >= mcd && f.secFlat[f.elem0[e] + 1] >= mcd;
}
// A maximum carried as a sum (chunkedSum): the largest of the chunks' largest, exact in any order.
struct DeepestOf {
  Real value = 0;
  DeepestOf& operator+=(const DeepestOf& o) { return value = std::max(value, o.value), *this; }
};
// A body contact's key: its CP, body, part and end (BodyContact::end; -1: the sphere's own place,
// or a box or cylinder contact). Only a contact of the same key is its memory: a sphere's contact
// held at an end node measures that node's section, not the section at the centre's place.
inline std::uint64_t bodyKey(Index cp, int body, int part, int end) {
  return (static_cast<std::uint64_t>(cp) << 32) | (static_cast<std::uint64_t>(body & 0x3fff) << 18) |
         (static_cast<std::uint64_t>(part & 0xffff) << 2) | static_cast<std::uint64_t>(end + 1);
}

}  // namespace stage
}  // namespace woven
