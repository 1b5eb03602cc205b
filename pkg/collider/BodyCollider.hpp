// Collider between the CPs and the parts of rigid bodies (a projectile, clamps): the broad phase of
// the body contacts. Few parts against many CPs, so a flat list per part with its own Verlet skin:
// the CPs whose broad-phase box (grown by their motion in the step) lies within `skin` of the part's
// box are listed, and the list holds until the body and the fastest CP together have travelled the
// skin since it was made (measured from the step's growths: O(CPs) compares, no box tests).
#pragma once
#include "bound/OBB.hpp"
#include "fabric/Fabric.hpp"
#include "shape/RigidBody.hpp"
#include <vector>

namespace woven {

struct BodyCandidate {
  Index cp;
  int body, part;
};

class BodyCollider {
 public:
  Real skin = 1e-4;  ///< [m] > 0

  /// Candidate (CP, body, part) triples into `out`, sorted by body, part, CP. `grown` are the CPs'
  /// broad-phase boxes, `grow` how far each CP can move in the step [m], dt the step [s].
  void collide(const Fabric& f, const std::vector<OBB>& grown, const std::vector<Real>& grow,
               const std::vector<RigidBody>& bodies, Real dt, std::vector<BodyCandidate>& out);
  long rebuilds = 0;  ///< lists made since the start

 private:
  std::vector<BodyCandidate> list_;
  Real travelled_ = 0;   // body + fastest CP travel since the list was made [m]
  std::size_t layout_ = 0;
  bool valid_ = false;
};

/// Axis-aligned half-widths of an OBB [m].
inline Vec3 aabbHalf(const OBB& b) { return b.axes.cwiseAbs() * b.extent; }

}  // namespace woven
