#include "collider/YarnTreeCollider.hpp"
#include "geom/SeparatingAxis.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {

// Interval of box b projected on the unit axis w: centre.w -/+ sum_i e_i |A_i.w|.
inline void project(const OBB& b, const Vec3& w, Real& lo, Real& hi) {
  const Real c = b.centre.dot(w);
  const Real r = b.extent[0] * std::abs(b.axes.col(0).dot(w)) + b.extent[1] * std::abs(b.axes.col(1).dot(w)) +
                 b.extent[2] * std::abs(b.axes.col(2).dot(w));
  lo = std::min(lo, c - r);
  hi = std::max(hi, c + r);
}

// Smallest box with the given axes holding boxes l and r (axes kept, centre and extents refitted).
inline void fitOnAxes(OBB& box, const OBB& l, const OBB& r) {
  Vec3 c = Vec3::Zero();
  for (int ax = 0; ax < 3; ++ax) {
    const Vec3 w = box.axes.col(ax);
    Real lo = INFINITY, hi = -INFINITY;
    project(l, w, lo, hi);
    project(r, w, lo, hi);
    c += 0.5 * (lo + hi) * w;
    box.extent[ax] = 0.5 * (hi - lo);
  }
  box.centre = c;
}

// Axes of a parent from its children: A0 along the chord between the children's centres, A2 the
// children's mean A2 made normal to it.
inline void chordAxes(OBB& box, const OBB& l, const OBB& r) {
  Vec3 A0 = r.centre - l.centre;
  if (A0.norm() < 1e-12 * (l.extent.norm() + r.extent.norm())) A0 = l.axes.col(0);
  A0.normalize();
  const Vec3 l2 = l.axes.col(2), r2 = r.axes.col(2);
  Vec3 A2 = l2 + (l2.dot(r2) < 0 ? Vec3(-r2) : r2);
  A2 -= A2.dot(A0) * A0;
  A2 = A2.norm() > 1e-9 ? Vec3(A2.normalized()) : A0.unitOrthogonal();
  box.axes.col(0) = A0;
  box.axes.col(1) = A2.cross(A0);
  box.axes.col(2) = A2;
}

inline Real volume(const OBB& b) { return b.extent[0] * b.extent[1] * b.extent[2]; }

}  // namespace

Index YarnTreeCollider::buildRange(Index lo, Index hi) {
  const Index me = static_cast<Index>(nodes_.size());
  nodes_.emplace_back();
  nodes_[me].lo = lo, nodes_[me].hi = hi;
  if (hi - lo > 1) {
    const Index mid = lo + (hi - lo) / 2;
    const Index l = buildRange(lo, mid);
    const Index r = buildRange(mid, hi);
    nodes_[me].left = l, nodes_[me].right = r;
  }
  return me;
}

void YarnTreeCollider::build(const Fabric& f) {
  nodes_.clear();
  root_.assign(f.yarns.size(), -1);
  layout_.clear();
  for (std::size_t y = 0; y < f.yarns.size(); ++y) {
    const Yarn& yarn = f.yarns[y];
    layout_.push_back(yarn.firstElem), layout_.push_back(yarn.nElems);
    if (yarn.nElems > 0) root_[y] = buildRange(yarn.firstElem, yarn.firstElem + yarn.nElems);
  }
}

long YarnTreeCollider::refitRange(const std::vector<OBB>& boxes, Index first, Index last) {
  long rebuilt = 0;
  for (Index k = last - 1; k >= first; --k) {  // children before parents
    Node& n = nodes_[k];
    if (n.leaf()) {
      n.box = boxes[n.lo];
      continue;
    }
    const OBB &l = nodes_[n.left].box, &r = nodes_[n.right].box;
    if (n.refVolume > 0) {
      fitOnAxes(n.box, l, r);
      if (volume(n.box) <= rebuildRatio * n.refVolume) continue;
    }
    chordAxes(n.box, l, r);  // first fit, or the quality degraded: rebuild this node's axes
    fitOnAxes(n.box, l, r);
    n.refVolume = std::max(volume(n.box), 1e-300);
    ++rebuilt;
  }
  return rebuilt;
}

long YarnTreeCollider::descend(const Fabric& f, Index p, Index q, const PairFilter& filter, std::vector<CPPair>& pairs,
                               std::vector<std::pair<Index, Index>>& stack) const {
  long tests = 0;
  stack.clear();
  stack.emplace_back(p, q);
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    const Node &a = nodes_[i], &b = nodes_[j];
    if (i == j) {  // a subtree against itself: its two halves against each other and themselves
      if (a.leaf()) continue;
      stack.emplace_back(a.left, a.right);
      stack.emplace_back(a.right, a.right);
      stack.emplace_back(a.left, a.left);
      continue;
    }
    ++tests;
    if (a.leaf() && b.leaf()) {  // the same test, in the same argument order, as SweepAndPrune
      const bool aFirst = a.lo < b.lo;
      const Index x = aFirst ? a.lo : b.lo, y = aFirst ? b.lo : a.lo;
      if (!filter.excluded(f, x, y) && obbOverlap(aFirst ? a.box : b.box, aFirst ? b.box : a.box))
        pairs.push_back({x, y});
      continue;
    }
    if (!obbOverlap(a.box, b.box)) continue;
    if (b.leaf() || (!a.leaf() && a.hi - a.lo >= b.hi - b.lo)) {
      stack.emplace_back(a.right, j);
      stack.emplace_back(a.left, j);
    } else {
      stack.emplace_back(i, b.right);
      stack.emplace_back(i, b.left);
    }
  }
  return tests;
}

void YarnTreeCollider::collide(const Fabric& f, const std::vector<OBB>& boxes, const PairFilter& filter,
                               std::vector<CPPair>& pairs, const std::vector<std::uint8_t>* dirty) {
  bool same = layout_.size() == 2 * f.yarns.size();
  for (std::size_t y = 0; same && y < f.yarns.size(); ++y)
    same = layout_[2 * y] == f.yarns[y].firstElem && layout_[2 * y + 1] == f.yarns[y].nElems;
  if (!same) build(f);
  // Each yarn's nodes are contiguous (built yarn after yarn). With `dirty`, only the flagged yarns'
  // boxes changed since the last call, so only their trees are refitted; each tree on its own (threads).
  const Index nY = static_cast<Index>(root_.size());
  perYarn_.assign(nY, 0);
  parallelForDynamic(nY, 2, threads(), [&](Index y) {
    if (root_[y] < 0 || (dirty && same && !(*dirty)[y])) return;
    Index end = static_cast<Index>(nodes_.size());
    for (Index z = y + 1; z < nY; ++z)
      if (root_[z] >= 0) {
        end = root_[z];
        break;
      }
    perYarn_[y] = refitRange(boxes, root_[y], end);
  });
  for (long r : perYarn_) stats.rebuiltNodes += r;
  pairs.clear();

  // Across yarns: sort the roots' world-axis-aligned extents along x and sweep (few yarns).
  struct Span {
    Real lo[3], hi[3];
    Index yarn;
  };
  std::vector<Span> spans;
  for (std::size_t y = 0; y < root_.size(); ++y) {
    if (root_[y] < 0) continue;
    const OBB& b = nodes_[root_[y]].box;
    const Vec3 half = b.axes.cwiseAbs() * b.extent;
    Span s;
    for (int k = 0; k < 3; ++k) s.lo[k] = b.centre[k] - half[k], s.hi[k] = b.centre[k] + half[k];
    s.yarn = static_cast<Index>(y);
    spans.push_back(s);
  }
  std::sort(spans.begin(), spans.end(),
            [](const Span& a, const Span& b) { return a.lo[0] < b.lo[0] || (a.lo[0] == b.lo[0] && a.yarn < b.yarn); });
  // The descents of each span (threads) into their own list; the lists joined and sorted: the same
  // pairs in the same order at any thread count.
  const Index nS = static_cast<Index>(spans.size());
  spanPairs_.resize(nS);
  perYarn_.assign(nS, 0);
  parallelForDynamic(nS, 2, threads(), [&](Index s) {
    std::vector<CPPair>& out = spanPairs_[s];
    out.clear();
    std::vector<std::pair<Index, Index>> stack;
    long tests = 0;
    const bool dirtyS = !dirty || (*dirty)[spans[s].yarn];
    if (dirtyS) tests += descend(f, root_[spans[s].yarn], root_[spans[s].yarn], filter, out, stack);  // self contact of the yarn
    for (Index t = s + 1; t < nS && spans[t].lo[0] <= spans[s].hi[0]; ++t) {
      if (!dirtyS && !(*dirty)[spans[t].yarn]) continue;
      if (spans[t].lo[1] > spans[s].hi[1] || spans[s].lo[1] > spans[t].hi[1] || spans[t].lo[2] > spans[s].hi[2] ||
          spans[s].lo[2] > spans[t].hi[2])
        continue;
      tests += descend(f, root_[spans[s].yarn], root_[spans[t].yarn], filter, out, stack);
    }
    perYarn_[s] = tests;
  });
  for (Index s = 0; s < nS; ++s) {
    pairs.insert(pairs.end(), spanPairs_[s].begin(), spanPairs_[s].end());
    stats.overlapTests += perYarn_[s];
  }
  std::sort(pairs.begin(), pairs.end());
}

}  // namespace woven
