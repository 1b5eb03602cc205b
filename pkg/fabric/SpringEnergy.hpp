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

}  // namespace woven
