#include "collider/GridCollider.hpp"
#include "geom/SegmentDistance.hpp"
#include "geom/SeparatingAxis.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

void GridCollider::CellTable::clear() {
  std::fill(keys_.begin(), keys_.end(), kFree);
  for (std::vector<Index>& c : cells_) c.clear();
  used_ = 0;
}

void GridCollider::CellTable::grow() {
  std::vector<std::uint64_t> keys(std::max<std::size_t>(1024, 2 * keys_.size()), kFree);
  std::vector<std::vector<Index>> cells(keys.size());
  keys.swap(keys_), cells.swap(cells_);
  mask_ = keys_.size() - 1;
  shift_ = 64 - __builtin_ctzll(keys_.size());
  for (std::size_t k = 0; k < keys.size(); ++k)
    if (keys[k] != kFree) {
      std::size_t s = slot(keys[k]);
      while (keys_[s] != kFree) s = (s + 1) & mask_;
      keys_[s] = keys[k], cells_[s] = std::move(cells[k]);
    }
}

std::vector<Index>& GridCollider::CellTable::at(std::uint64_t key) {
  if (2 * (used_ + 1) > keys_.size()) grow();
  std::size_t s = slot(key);
  while (keys_[s] != key) {
    if (keys_[s] == kFree) {
      keys_[s] = key, ++used_;
      break;
    }
    s = (s + 1) & mask_;
  }
  return cells_[s];
}

const std::vector<Index>* GridCollider::CellTable::find(std::uint64_t key) const {
  if (keys_.empty()) return nullptr;
  for (std::size_t s = slot(key);; s = (s + 1) & mask_) {
    if (keys_[s] == key) return &cells_[s];
    if (keys_[s] == kFree) return nullptr;
  }
}

void GridCollider::aabb(const std::vector<OBB>& boxes, Index i) {
  const Vec3 half = boxes[i].axes.cwiseAbs() * boxes[i].extent;
  aabb_[i] = {boxes[i].centre - half, boxes[i].centre + half};
}

GridCollider::Cell GridCollider::cellOf(const Vec3& x) const {
  return {static_cast<std::int64_t>(std::floor(x.x() * inverse_)), static_cast<std::int64_t>(std::floor(x.y() * inverse_)),
          static_cast<std::int64_t>(std::floor(x.z() * inverse_))};
}

void GridCollider::insert(Index i) {
  cellLo_[i] = cellOf(aabb_[i].lo), cellHi_[i] = cellOf(aabb_[i].hi);
  for (std::int64_t x = cellLo_[i].x; x <= cellHi_[i].x; ++x)
    for (std::int64_t y = cellLo_[i].y; y <= cellHi_[i].y; ++y)
      for (std::int64_t z = cellLo_[i].z; z <= cellHi_[i].z; ++z) cells_.at(key(x, y, z)).push_back(i);
  held_[i] = 1;
}

void GridCollider::remove(Index i) {
  for (std::int64_t x = cellLo_[i].x; x <= cellHi_[i].x; ++x)
    for (std::int64_t y = cellLo_[i].y; y <= cellHi_[i].y; ++y)
      for (std::int64_t z = cellLo_[i].z; z <= cellHi_[i].z; ++z) {
        std::vector<Index>& in = cells_.at(key(x, y, z));
        const auto it = std::find(in.begin(), in.end(), i);
        if (it != in.end()) *it = in.back(), in.pop_back();
      }
  held_[i] = 0;
}

// Every live CP entered afresh, the cells as large as the largest live AABB side (a maximum per
// fixed chunk, then over the chunks: exact in any order). False when no live CP has a box.
bool GridCollider::rebuild(const Fabric& f, const std::vector<OBB>& boxes) {
  const Index n = static_cast<Index>(boxes.size());
  constexpr Index kChunk = 1024;
  const Index chunks = chunkCount(n, kChunk);
  aabb_.resize(n), cellLo_.resize(n), cellHi_.resize(n);
  held_.assign(static_cast<std::size_t>(n), 0);
  chunkSide_.assign(chunks, 0);
  parallelFor(chunks, 2, threads(), [&](Index t) {
    Real side = 0;
    for (Index i = t * kChunk, end = std::min(n, i + kChunk); i < end; ++i) {
      aabb(boxes, i);
      if (f.alive[i]) side = std::max(side, (aabb_[i].hi - aabb_[i].lo).maxCoeff());
    }
    chunkSide_[t] = side;
  });
  Real h = 0;
  for (Real side : chunkSide_) h = std::max(h, side);
  cells_.clear();
  if (!(h > 0) || !std::isfinite(h)) {
    cellSize = inverse_ = 0;
    return false;
  }
  cellSize = h * 1.0000001;  // every AABB then spans at most two cells per axis
  inverse_ = 1 / cellSize;
  for (Index i = 0; i < n; ++i)
    if (f.alive[i]) insert(i);
  ++rebuilds;
  return true;
}

void GridCollider::collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter,
                           std::vector<CPPair>& pairs, const std::vector<std::uint8_t>* dirty) {
  pairs.clear();
  const Index n = static_cast<Index>(boxes.size());
  const int nThreads = threads();
  // The grid follows the boxes: a partial call moves the flagged CPs (a broken one leaves it), unless
  // one spans too many cells or the grid holds other CPs; then, as a full call, it is built afresh.
  bool fresh = !dirty || static_cast<Index>(aabb_.size()) != n || !(cellSize > 0);
  flagged_.clear();
  if (dirty)
    for (Index i = 0; i < n; ++i)
      if ((*dirty)[i]) flagged_.push_back(i);
  if (!fresh) {
    // A CP that stays in the cells it is in (most: its box moved within the cell size) keeps its
    // entries; the pairs do not depend on the order of a cell's entries (each CP's list is sorted).
    moving_.clear();
    for (Index i : flagged_) {
      aabb(boxes, i);
      const Cell a = cellOf(aabb_[i].lo), b = cellOf(aabb_[i].hi);
      if (held_[i] && f.alive[i] && a == cellLo_[i] && b == cellHi_[i]) continue;
      if (held_[i]) remove(i);
      if (!f.alive[i]) continue;  // a broken CP leaves the grid, however far its box has flown
      moving_.push_back(i);
      fresh = fresh || b.x - a.x >= kMaxSpan || b.y - a.y >= kMaxSpan || b.z - a.z >= kMaxSpan;
    }
    if (!fresh)
      for (Index i : moving_) insert(i);
  }
  if (fresh && !rebuild(f, boxes)) return;

  // The CPs that look in their cells (all, or the flagged ones), by fixed chunks (threads), each
  // listing its pairs in CP order, joined in chunk order (the same list at any thread count). Each
  // CP meets the later CPs of its cells, or with `dirty` every CP but the earlier flagged ones (a
  // flagged pair once, from its lower CP): a pair (j, i) with j < i is then listed from i, and the
  // list is sorted at the end. The joined list is in CP order whatever the chunks, so their size
  // only spreads the work: a partial call looks for a few hundred CPs (~4 us each), and chunks of
  // 1024 kept them on one thread (the default impact's broad phase 1.2x on 2 threads).
  const auto flagged = [dirty](Index i) { return !dirty || (*dirty)[i]; };
  const Index looking = dirty ? static_cast<Index>(flagged_.size()) : n;
  const auto cp = [&](Index k) { return dirty ? flagged_[k] : k; };
  const Index kChunk = dirty ? 32 : 1024;
  const Index chunks = chunkCount(looking, kChunk);
  chunkPairs_.resize(chunks);
  chunkTests_.assign(chunks, 0);
  parallelForDynamic(chunks, 2, nThreads, [&](Index t) {
    std::vector<CPPair>& out = chunkPairs_[t];
    out.clear();
    std::vector<Index> mine;
    for (Index k = t * kChunk, end = std::min(looking, k + kChunk); k < end; ++k) {
      const Index i = cp(k);
      if (!held_[i]) continue;
      mine.clear();
      const Aabb bi = aabb_[i];
      const Cell ci = cellLo_[i];
      for (std::int64_t x = cellLo_[i].x; x <= cellHi_[i].x; ++x)
        for (std::int64_t y = cellLo_[i].y; y <= cellHi_[i].y; ++y)
          for (std::int64_t z = cellLo_[i].z; z <= cellHi_[i].z; ++z) {
            const std::vector<Index>* cell = cells_.find(key(x, y, z));
            if (!cell) continue;
            for (const Index j : *cell) {
              if (j == i || (j < i && flagged(j))) continue;
              const Aabb& bj = aabb_[j];
              if ((bi.hi.array() < bj.lo.array()).any() || (bj.hi.array() < bi.lo.array()).any()) continue;
              // The pair belongs to the cell of its AABB intersection's lowest corner: once only.
              // That cell is the larger of the two lowest cells on each axis (cellOf is monotone).
              const Cell& cj = cellLo_[j];
              if (std::max(ci.x, cj.x) != x || std::max(ci.y, cj.y) != y || std::max(ci.z, cj.z) != z) continue;
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
