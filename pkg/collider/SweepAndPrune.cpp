#include "collider/SweepAndPrune.hpp"
#include "geom/SeparatingAxis.hpp"
#include <algorithm>
#include <numeric>

namespace woven {

void SweepAndPrune::collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter,
                            std::vector<CPPair>& pairs) {
  const Index n = static_cast<Index>(boxes.size());
  lo_.resize(3 * n), hi_.resize(3 * n);
  for (Index e = 0; e < n; ++e) {
    const Vec3 half = boxes[e].axes.cwiseAbs() * boxes[e].extent;
    for (int k = 0; k < 3; ++k) lo_[3 * e + k] = boxes[e].centre[k] - half[k], hi_[3 * e + k] = boxes[e].centre[k] + half[k];
  }
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0);
  std::sort(order_.begin(), order_.end(), [&](Index a, Index b) { return lo_[3 * a] < lo_[3 * b] || (lo_[3 * a] == lo_[3 * b] && a < b); });
  pairs.clear();
  for (Index s = 0; s < n; ++s) {
    const Index a = order_[s];
    for (Index t = s + 1; t < n && lo_[3 * order_[t]] <= hi_[3 * a]; ++t) {
      const Index b = order_[t];
      if (lo_[3 * b + 1] > hi_[3 * a + 1] || lo_[3 * a + 1] > hi_[3 * b + 1] || lo_[3 * b + 2] > hi_[3 * a + 2] ||
          lo_[3 * a + 2] > hi_[3 * b + 2])
        continue;
      const Index x = std::min(a, b), y = std::max(a, b);
      if (filter.excluded(f, x, y)) continue;
      ++overlapTests;
      if (obbOverlap(boxes[x], boxes[y])) pairs.push_back({x, y});
    }
  }
  std::sort(pairs.begin(), pairs.end());
}

}  // namespace woven
