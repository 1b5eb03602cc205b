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
  const int nThreads = threads();
  // The AABBs and the cell size, the largest live AABB side (a maximum per fixed chunk, then over
  // the chunks: exact in any order).
  constexpr Index kChunk = 1024;
  const Index chunks = chunkCount(n, kChunk);
  lo_.resize(n), hi_.resize(n);
  chunkSide_.assign(chunks, 0);
  parallelFor(chunks, 2, nThreads, [&](Index t) {
    Real side = 0;
    for (Index i = t * kChunk, end = std::min(n, i + kChunk); i < end; ++i) {
      const Vec3 half = boxes[i].axes.cwiseAbs() * boxes[i].extent;
      lo_[i] = boxes[i].centre - half, hi_[i] = boxes[i].centre + half;
      if (f.alive[i]) side = std::max(side, 2 * half.maxCoeff());
    }
    chunkSide_[t] = side;
  });
  Real h = 0;
  for (Real side : chunkSide_) h = std::max(h, side);
  if (!(h > 0) || !std::isfinite(h)) return;
  h *= 1.0000001;  // every AABB then spans at most two cells per axis
  cellSize = h;
  const Real ih = 1 / h;
  // The cells of each CP: its range of cells per axis and their count (threads), their starts, then
  // the cells written with their slots (threads).
  cellLo_.resize(n), cellHi_.resize(n);
  cellBegin_.resize(n + 1);
  parallelFor(n, kParallelGrain, nThreads, [&](Index i) {
    const auto cell = [ih](const Vec3& x) {
      return Cell{static_cast<std::int64_t>(std::floor(x.x() * ih)), static_cast<std::int64_t>(std::floor(x.y() * ih)),
                  static_cast<std::int64_t>(std::floor(x.z() * ih))};
    };
    const Cell lo = cell(lo_[i]), hi = cell(hi_[i]);
    cellLo_[i] = lo, cellHi_[i] = hi;
    cellBegin_[i + 1] = f.alive[i] ? static_cast<Index>((hi.x - lo.x + 1) * (hi.y - lo.y + 1) * (hi.z - lo.z + 1)) : 0;
  });
  cellBegin_[0] = 0;
  for (Index i = 0; i < n; ++i) cellBegin_[i + 1] += cellBegin_[i];
  const std::size_t cells = static_cast<std::size_t>(cellBegin_[n]);
  std::size_t size = 1;
  while (size < 2 * cells) size <<= 1;
  const std::uint64_t mask = size - 1;
  cellOf_.resize(cells), cellSlot_.resize(cells), cellCP_.resize(cells);
  parallelFor(n, kParallelGrain, nThreads, [&](Index i) {
    if (!f.alive[i]) return;
    const Cell lo = cellLo_[i], hi = cellHi_[i];
    Index k = cellBegin_[i];
    for (std::int64_t x = lo.x; x <= hi.x; ++x)
      for (std::int64_t y = lo.y; y <= hi.y; ++y)
        for (std::int64_t z = lo.z; z <= hi.z; ++z, ++k) {
          cellOf_[k] = {x, y, z}, cellCP_[k] = i;
          cellSlot_[k] = static_cast<std::uint32_t>(slotOf(x, y, z, mask));
        }
  });

  // Hash table of cells: count, prefix sums, scatter in cell order (entries of a slot in ascending
  // CP order: a stable counting sort of the cells by slot). The slots are split into ranges, one per
  // thread; each thread reads every cell and writes only the slots of its range and their entries,
  // so any split gives the same table.
  const int parts = nThreads;
  slotCount_.resize(size + 1);
  fill_.resize(size);
  partTotal_.resize(static_cast<std::size_t>(parts) + 1);
  const auto range = [&](Index p, std::size_t& s0, std::size_t& s1) { s0 = size * p / parts, s1 = size * (p + 1) / parts; };
  slotCount_[0] = 0;
  parallelFor(parts, 1, nThreads, [&](Index p) {
    std::size_t s0, s1;
    range(p, s0, s1);
    std::fill(slotCount_.begin() + s0 + 1, slotCount_.begin() + s1 + 1, 0);
    for (std::uint32_t s : cellSlot_)
      if (s >= s0 && s < s1) ++slotCount_[s + 1];
    for (std::size_t s = s0 + 1; s < s1; ++s) slotCount_[s + 1] += slotCount_[s];  // within the range
    partTotal_[p + 1] = s1 > s0 ? slotCount_[s1] : 0;
  });
  partTotal_[0] = 0;
  for (int p = 0; p < parts; ++p) partTotal_[p + 1] += partTotal_[p];
  slotItem_.resize(cells), slotCell_.resize(cells);
  parallelFor(parts, 1, nThreads, [&](Index p) {
    std::size_t s0, s1;
    range(p, s0, s1);
    const std::uint32_t offset = partTotal_[p];
    if (offset > 0)
      for (std::size_t s = s0; s < s1; ++s) slotCount_[s + 1] += offset;
    if (s1 > s0) {
      fill_[s0] = offset;
      std::copy(slotCount_.begin() + s0 + 1, slotCount_.begin() + s1, fill_.begin() + s0 + 1);
    }
    for (std::size_t k = 0; k < cells; ++k)
      if (const std::uint32_t s = cellSlot_[k]; s >= s0 && s < s1) {
        const std::uint32_t at = fill_[s]++;
        slotItem_[at] = cellCP_[k], slotCell_[at] = static_cast<Index>(k);
      }
  });

  // Each CP with the later CPs of its cells: fixed chunks of CPs (threads), each listing its pairs in
  // CP order, joined in chunk order (the same list at any thread count). With `dirty`, each flagged
  // CP with every CP of its cells, a flagged pair once (from its lower CP): a pair (j, i) with j < i
  // is then listed from i, and the list is sorted at the end.
  const auto flagged = [dirty](Index i) { return !dirty || (*dirty)[i]; };
  chunkPairs_.resize(chunks);
  chunkTests_.assign(chunks, 0);
  parallelForDynamic(chunks, 2, nThreads, [&](Index t) {
    std::vector<CPPair>& out = chunkPairs_[t];
    out.clear();
    std::vector<Index> mine;
    for (Index i = t * kChunk, end = std::min(n, i + kChunk); i < end; ++i) {
      if (!flagged(i)) continue;
      mine.clear();
      for (Index k = cellBegin_[i]; k < cellBegin_[i + 1]; ++k) {
        const Cell& c = cellOf_[k];
        const std::uint32_t s = cellSlot_[k];
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
  joinChunks(chunkPairs_, pairs, nThreads);
  for (Index t = 0; t < chunks; ++t) overlapTests += chunkTests_[t];
  if (dirty) std::sort(pairs.begin(), pairs.end());
}

}  // namespace woven
