#include "collider/BodyCollider.hpp"
#include <algorithm>
#include <numeric>

namespace woven {

namespace {
constexpr int kLeafParts = 4;
}

void PartTree::build(const RigidBody& b) {
  const std::size_t n = b.parts.size();
  std::vector<Vec3> lo(n), hi(n);
  reach = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const RigidPart& p = b.parts[k];
    if (p.type == RigidPart::Type::Triangle) {
      lo[k] = hi[k] = p.offset + p.ori * p.vert[0];
      for (int j = 1; j < 3; ++j) {
        const Vec3 v = p.offset + p.ori * p.vert[j];
        lo[k] = lo[k].cwiseMin(v), hi[k] = hi[k].cwiseMax(v);
      }
    } else {  // the part's box (RigidBody::partBox) in the body frame
      RigidBody local = b;
      local.pos = Vec3::Zero(), local.ori = Quat::Identity();
      const OBB box = local.partBox(k);
      lo[k] = box.centre - aabbHalf(box), hi[k] = box.centre + aabbHalf(box);
    }
    reach = std::max(reach, p.offset.norm() + b.partReach(k));
  }
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0);
  nodes_.clear();
  nodes_.reserve(2 * n / kLeafParts + 2);
  if (n) split(0, static_cast<int>(n), lo, hi);
  id = b.id, parts = n;
}

int PartTree::split(int first, int count, const std::vector<Vec3>& lo, const std::vector<Vec3>& hi) {
  const int me = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Vec3 l = lo[order_[first]], h = hi[order_[first]], cl = 0.5 * (l + h), ch = cl;
  for (int k = first; k < first + count; ++k) {
    const int q = order_[k];
    l = l.cwiseMin(lo[q]), h = h.cwiseMax(hi[q]);
    const Vec3 c = 0.5 * (lo[q] + hi[q]);
    cl = cl.cwiseMin(c), ch = ch.cwiseMax(c);
  }
  nodes_[me].lo = l, nodes_[me].hi = h;
  if (count <= kLeafParts) {
    nodes_[me].first = first, nodes_[me].count = count;
    return me;
  }
  // The median along the longest axis of the centres (ties by index: the same tree every build).
  int axis = 0;
  (ch - cl).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                   [&](int a, int b) {
                     const Real ca = lo[a][axis] + hi[a][axis], cb = lo[b][axis] + hi[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const int left = split(first, half, lo, hi);
  const int right = split(first + half, count - half, lo, hi);
  nodes_[me].left = left, nodes_[me].right = right;
  return me;
}

void PartTree::query(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const {
  if (nodes_.empty()) return;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top) {
    const Node& nd = nodes_[stack[--top]];
    if ((nd.hi.array() < lo.array()).any() || (nd.lo.array() > hi.array()).any()) continue;
    if (nd.count) {
      out.insert(out.end(), order_.begin() + nd.first, order_.begin() + nd.first + nd.count);
      continue;
    }
    stack[top++] = nd.right, stack[top++] = nd.left;
  }
}

void BodyCollider::collide(const Fabric& f, const std::vector<OBB>& grown, const std::vector<Real>& grow,
                           const std::vector<RigidBody>& bodies, Real dt, std::vector<BodyCandidate>& out) {
  Real fabricStep = 0, bodyStep = 0;
  for (Real g : grow) fabricStep = std::max(fabricStep, g);
  trees_.resize(bodies.size());
  std::size_t layout = 0;
  for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
    const RigidBody& b = bodies[bi];
    layout = layout * 31 + b.parts.size() + 1;
    Real reach = 0;  // farthest a part's point goes in the step
    if (b.parts.size() >= kTreeParts) {
      PartTree& t = trees_[bi];
      if (t.id != b.id || t.parts != b.parts.size()) t.build(b);
      reach = b.angVel.norm() * t.reach;
    } else {
      for (std::size_t k = 0; k < b.parts.size(); ++k)
        reach = std::max(reach, b.angVel.norm() * ((b.partCentre(k) - b.pos).norm() + aabbHalf(b.partBox(k)).norm()));
    }
    bodyStep = std::max(bodyStep, dt * (b.vel.norm() + reach));
  }
  travelled_ += fabricStep + bodyStep;
  if (!(valid_ && layout == layout_ && travelled_ <= skin)) {
    list_.clear();
    const Vec3 pad = Vec3::Constant(skin + bodyStep);
    for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
      const RigidBody& b = bodies[bi];
      if (b.parts.size() >= kTreeParts) {
        // The body's box in the global frame, then each CP near it against the tree in the body frame.
        const PartTree& t = trees_[bi];
        const Mat3 R = b.ori.toRotationMatrix();
        const Vec3 rootC = 0.5 * (t.rootLo() + t.rootHi()), rootH = 0.5 * (t.rootHi() - t.rootLo());
        const Vec3 c = b.pos + R * rootC, h = R.cwiseAbs() * rootH + pad;
        found_.clear();
        for (Index e = 0; e < f.nElems(); ++e) {
          if (!f.alive[e]) continue;
          const Vec3 he = aabbHalf(grown[e]);
          if (((grown[e].centre - c).cwiseAbs() - he - h).maxCoeff() > 0) continue;
          const Vec3 cl = R.transpose() * (grown[e].centre - b.pos), hl = R.transpose().cwiseAbs() * he + pad;
          hits_.clear();
          t.query(cl - hl, cl + hl, hits_);
          for (int k : hits_) found_.emplace_back(k, e);
        }
        std::sort(found_.begin(), found_.end());  // by part, then CP: the order of the flat lists
        for (const auto& [k, e] : found_) list_.push_back({e, static_cast<int>(bi), k});
        continue;
      }
      for (std::size_t k = 0; k < b.parts.size(); ++k) {
        const OBB box = b.partBox(k);
        const Vec3 lo = box.centre - aabbHalf(box) - pad;
        const Vec3 hi = box.centre + aabbHalf(box) + pad;
        for (Index e = 0; e < f.nElems(); ++e) {
          if (!f.alive[e]) continue;
          const Vec3 h = aabbHalf(grown[e]);
          if (((grown[e].centre + h).array() >= lo.array()).all() && ((grown[e].centre - h).array() <= hi.array()).all())
            list_.push_back({e, static_cast<int>(bi), static_cast<int>(k)});
        }
      }
    }
    travelled_ = 0;
    valid_ = true;
    layout_ = layout;
    ++rebuilds;
  }
  out.clear();
  for (const BodyCandidate& c : list_)
    if (f.alive[c.cp]) out.push_back(c);
}

}  // namespace woven
