#include "collider/GridCollider.hpp"
#include "geom/SegmentDistance.hpp"
#include "geom/SeparatingAxis.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {
inline std::uint64_t slotOf(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t mask) {
  // Large odd multipliers spread neighbouring cells over the table (Teschner et al. 2003).
  const std::uint64_t h = static_cast<std::uint64_t>(x) * 73856093ULL ^ static_cast<std::uint64_t>(y) * 19349663ULL ^
                          static_cast<std::uint64_t>(z) * 83492791ULL;
  return (h ^ (h >> 29)) & mask;
}
}  // namespace

void GridCollider::collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter,
                           std::vector<CPPair>& pairs, const std::vector<std::uint8_t>* dirty) {
  pairs.clear();
  const Index n = static_cast<Index>(boxes.size());
  lo_.resize(n), hi_.resize(n);
  Real h = 0;
  for (Index i = 0; i < n; ++i) {
    const Vec3 half = boxes[i].axes.cwiseAbs() * boxes[i].extent;
    lo_[i] = boxes[i].centre - half, hi_[i] = boxes[i].centre + half;
    if (f.alive[i]) h = std::max(h, 2 * half.maxCoeff());
  }
  if (!(h > 0) || !std::isfinite(h)) return;
  h *= 1.0000001;  // every AABB then spans at most two cells per axis
  cellSize = h;
  const Real ih = 1 / h;

  // The cells of each CP.
  cellOf_.clear();
  cellBegin_.assign(n + 1, 0);
  for (Index i = 0; i < n; ++i) {
    cellBegin_[i] = static_cast<Index>(cellOf_.size());
    if (!f.alive[i]) continue;
    const std::int64_t x0 = static_cast<std::int64_t>(std::floor(lo_[i].x() * ih)), x1 = static_cast<std::int64_t>(std::floor(hi_[i].x() * ih));
    const std::int64_t y0 = static_cast<std::int64_t>(std::floor(lo_[i].y() * ih)), y1 = static_cast<std::int64_t>(std::floor(hi_[i].y() * ih));
    const std::int64_t z0 = static_cast<std::int64_t>(std::floor(lo_[i].z() * ih)), z1 = static_cast<std::int64_t>(std::floor(hi_[i].z() * ih));
    for (std::int64_t x = x0; x <= x1; ++x)
      for (std::int64_t y = y0; y <= y1; ++y)
        for (std::int64_t z = z0; z <= z1; ++z) cellOf_.push_back({x, y, z});
  }
  cellBegin_[n] = static_cast<Index>(cellOf_.size());

  // Hash table of cells: count, prefix sums, scatter (entries of a slot in ascending CP order).
  std::size_t size = 1;
  while (size < 2 * cellOf_.size()) size <<= 1;
  const std::uint64_t mask = size - 1;
  slotCount_.assign(size + 1, 0);
  for (const Cell& c : cellOf_) ++slotCount_[slotOf(c.x, c.y, c.z, mask) + 1];
  for (std::size_t s = 0; s < size; ++s) slotCount_[s + 1] += slotCount_[s];
  slotItem_.resize(cellOf_.size()), slotCell_.resize(cellOf_.size());
  fill_.assign(slotCount_.begin(), slotCount_.end() - 1);
  for (Index i = 0; i < n; ++i)
    for (Index k = cellBegin_[i]; k < cellBegin_[i + 1]; ++k) {
      const Cell& c = cellOf_[k];
      const std::uint32_t at = fill_[slotOf(c.x, c.y, c.z, mask)]++;
      slotItem_[at] = i, slotCell_[at] = k;
    }

  // Each CP with the later CPs of its cells: fixed chunks of CPs (threads), each listing its pairs in
  // CP order, joined in chunk order (the same list at any thread count). With `dirty`, each flagged
  // CP with every CP of its cells, a flagged pair once (from its lower CP): a pair (j, i) with j < i
  // is then listed from i, and the list is sorted at the end.
  const auto flagged = [dirty](Index i) { return !dirty || (*dirty)[i]; };
  constexpr Index kChunk = 1024;
  const Index chunks = chunkCount(n, kChunk);
  chunkPairs_.resize(chunks);
  chunkTests_.assign(chunks, 0);
  parallelForDynamic(chunks, 2, threads(), [&](Index t) {
    std::vector<CPPair>& out = chunkPairs_[t];
    out.clear();
    std::vector<Index> mine;
    for (Index i = t * kChunk, end = std::min(n, i + kChunk); i < end; ++i) {
      if (!flagged(i)) continue;
      mine.clear();
      for (Index k = cellBegin_[i]; k < cellBegin_[i + 1]; ++k) {
        const Cell& c = cellOf_[k];
        const std::uint64_t s = slotOf(c.x, c.y, c.z, mask);
        for (std::uint32_t at = slotCount_[s]; at < slotCount_[s + 1]; ++at) {
          const Index j = slotItem_[at];
          if (j == i || (j < i && flagged(j))) continue;
          const Cell& cj = cellOf_[slotCell_[at]];
          if (cj.x != c.x || cj.y != c.y || cj.z != c.z) continue;  // another cell in the same slot
          if ((hi_[i].array() < lo_[j].array()).any() || (hi_[j].array() < lo_[i].array()).any()) continue;
          // The pair belongs to the cell of its AABB intersection's lowest corner: once only.
          const Vec3 corner = lo_[i].cwiseMax(lo_[j]);
          if (static_cast<std::int64_t>(std::floor(corner.x() * ih)) != c.x ||
              static_cast<std::int64_t>(std::floor(corner.y() * ih)) != c.y ||
              static_cast<std::int64_t>(std::floor(corner.z() * ih)) != c.z)
            continue;
          const Index lo = std::min(i, j), hi = std::max(i, j);  // the full phase's argument order
          if (filter.excluded(f, lo, hi)) continue;
          ++chunkTests_[t];
          // A point between the two axes answers most overlapping pairs (the boxes hold their CPs)
          const Index a = f.elem0[lo], b = f.elem0[hi];
          const Vec3 mid = closestMidpoint(f.pos[a], f.pos[a + 1], f.pos[b], f.pos[b + 1],
                                           closestSegmentSegment(f.pos[a], f.pos[a + 1], f.pos[b], f.pos[b + 1]));
          if (obbOverlap(boxes[lo], boxes[hi], mid)) mine.push_back(j);
        }
      }
      std::sort(mine.begin(), mine.end());
      for (Index j : mine) out.push_back({std::min(i, j), std::max(i, j)});
    }
  });
  for (Index t = 0; t < chunks; ++t) {
    pairs.insert(pairs.end(), chunkPairs_[t].begin(), chunkPairs_[t].end());
    overlapTests += chunkTests_[t];
  }
  if (dirty) std::sort(pairs.begin(), pairs.end());
}

}  // namespace woven
