// What a collider hands the narrow phase: pairs of CPs (a < b) whose broad-phase boxes overlap.
// Both colliders (the OBB tree and the sweep-and-prune reference) apply the same final test to the
// same boxes, so on the same input they return the same sorted list.
#pragma once
#include "core/Parallel.hpp"
#include "bound/OBB.hpp"
#include "collider/CrossingFootprints.hpp"
#include "fabric/Fabric.hpp"
#include <cmath>
#include <vector>

namespace woven {

struct CPPair {
  Index a, b;  ///< CP indices, a < b
  bool operator<(const CPPair& o) const { return a < o.a || (a == o.a && b < o.b); }
  bool operator==(const CPPair& o) const { return a == o.a && b == o.b; }
};

/// CPs of one yarn this many elements apart or closer never collide with each other: at least the
/// CPs that share a node (1), and, per yarn, every pair closer along the yarn than its section
/// diameter at rest: 1 + ceil(2 r0 / l0_min) (they are the yarn's own body: a yarn of 0.27 mm
/// diameter cut into 0.19 mm CPs overlaps itself over three CPs).
/// And pairs of two yarns that a persistent crossing stands for (CrossingFootprints) never enter the
/// general pipeline.
struct PairFilter {
  Index selfExclude = 1;          ///< the user's minimum
  std::vector<Index> yarnExclude; ///< per yarn, from its sections and CP lengths (set by configure)
  const CrossingFootprints* crossings = nullptr;  ///< the live crossings' footprints (none: null)
  /// `widen`: the widest semi-axis a section can reach, over r0 (1 for round sections; the gap
  /// model measures flattened widths side by side, up to r0 / (1 - MCD), and a yarn folded back on
  /// itself cannot hold its two legs that far apart across fewer CPs: they would fight its springs).
  void configure(const Fabric& f, Index minimum, Real widen = 1) {
    selfExclude = minimum;
    yarnExclude.assign(f.yarns.size(), minimum);
    for (std::size_t y = 0; y < f.yarns.size(); ++y) {
      const Yarn& Y = f.yarns[y];
      Real r = 0, l = INFINITY;
      for (Index k = Y.firstNode; k < Y.firstNode + Y.nNodes; ++k) r = std::max(r, f.secRadius[k]);
      for (Index e = Y.firstElem; e < Y.firstElem + Y.nElems; ++e) l = std::min(l, f.restLength[e]);
      if (Y.nElems > 0) yarnExclude[y] = std::max(minimum, 1 + static_cast<Index>(std::ceil(2 * widen * r / l)));
    }
  }
  bool excluded(const Fabric& f, Index a, Index b) const {
    if (!f.alive[a] || !f.alive[b]) return true;
    const Index y = f.elemYarn[a];
    if (y != f.elemYarn[b]) return crossings && crossings->covers(a, b);
    const Index k = static_cast<std::size_t>(y) < yarnExclude.size() ? yarnExclude[y] : selfExclude;
    return std::abs(a - b) <= k;
  }
};

/// Broad-phase box of each CP: its bound grown by `grow[e]` [m] on every side (the distance its
/// nodes can travel within the step), so no pair that meets during the step is missed.
inline void growBoxes(const std::vector<OBB>& bounds, const std::vector<Real>& grow, std::vector<OBB>& out) {
  out.resize(bounds.size());
  parallelFor(static_cast<Index>(out.size()), kParallelGrain, threads(), [&](Index e) {
    out[e] = bounds[e];
    out[e].extent.array() += grow[e];
  });
}

}  // namespace woven
