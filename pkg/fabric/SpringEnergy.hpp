// Spring energy of one CP at the current positions: what a change of positions outside the
// integrator (positional correction, position projection) puts into the chain, for the books.
#pragma once
#include "fabric/Fabric.hpp"

namespace woven {

/// 1/2 K (l - l0)^2 of CP e (0 while slack for tension-only yarns) [J].
inline Real springEnergy(const Fabric& f, Index e) {
  const Real stretch = (f.pos[f.elem0[e] + 1] - f.pos[f.elem0[e]]).norm() - f.restLength[e];
  if (stretch < 0 && f.materials[f.yarns[f.elemYarn[e]].material].tensionOnly) return 0;
  return 0.5 * f.stiffness[e] * stretch * stretch;
}

/// Axial spring force of CP e on its first node [N] (the second gets its opposite): K (l - l0) along
/// the CP, 0 while slack for tension-only yarns. The dashpot is left out (it depends on velocities).
inline Vec3 springForce(const Fabric& f, Index e) {
  const Vec3 d = f.pos[f.elem0[e] + 1] - f.pos[f.elem0[e]];
  const Real l = d.norm(), stretch = l - f.restLength[e];
  if (!(l > 0) || (stretch < 0 && f.materials[f.yarns[f.elemYarn[e]].material].tensionOnly)) return Vec3::Zero();
  return (f.stiffness[e] * stretch / l) * d;
}

}  // namespace woven
