// The collision stage's CP-body contacts: the rigid parts' candidates (BodyCollider), their contacts
// measured with the memory of the last step's (geom/BodyContact), and the bodies' overlap query.
#include "engine/CollisionStage.hpp"
#include "core/Parallel.hpp"
#include "engine/StageUtil.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

using namespace stage;  // engine/StageUtil.hpp

void CollisionStage::narrowBodies(const Fabric& f, Real dt) {
  // The last step's contacts, by CP, body and part: the gap model's measure memory (bodyGap).
  heldBody_.swap(bodyContacts_);
  if (heldFor_ != bodies.size() || forgetHeld_) heldBody_.clear();  // bodies added or removed: indices moved
  heldFor_ = bodies.size(), forgetHeld_ = false;
  heldKeys_.clear();
  for (std::size_t q = 0; q < heldBody_.size(); ++q)
    heldKeys_.emplace_back(bodyKey(heldBody_[q].cp, heldBody_[q].body, heldBody_[q].part, heldBody_[q].end), q);
  std::sort(heldKeys_.begin(), heldKeys_.end());
  bodyContacts_.clear();
  bodyPairs_.clear();
  if (bodies.empty()) return;
  bodyCollider.collide(f, grown_, grow_, bodies, dt, bodyPairs_);
  measureBodies(f, dt);
}

// The body contacts of the candidates (bodyPairs_) with the sections as they stand, each with the
// last step's contact of its CP, body and part (heldBody_; a sphere's at the centre's place, not an
// end node's) as its measure memory.
void CollisionStage::measureBodies(const Fabric& f, Real dt) {
  bodyContacts_.clear();
  BodyContact c[2];
  const bool gapModel = params_.model == ContactModel::Gap;
  // The position projection may move a node by this much after the drift (toward the body, pushed
  // by its other contacts): such contacts are listed too, as the CP pairs are (narrow).
  const Real projected = projectionReach(dt);
  const auto heldAt = [&](const BodyCandidate& pc, int end) -> const BodyContact* {
    const std::uint64_t key = bodyKey(pc.cp, pc.body, pc.part, end);
    const auto it = std::lower_bound(heldKeys_.begin(), heldKeys_.end(), std::make_pair(key, std::size_t(0)));
    return it != heldKeys_.end() && it->first == key ? &heldBody_[it->second] : nullptr;
  };
  for (const BodyCandidate& pc : bodyPairs_) {
    const BodyContact* held = gapModel ? heldAt(pc, -1) : nullptr;
    // A triangle's face contacts at the end nodes hold their memories apart (the two sections differ).
    const BodyContact* ends[2] = {nullptr, nullptr};
    const bool triangle = gapModel && bodies[pc.body].parts[pc.part].type == RigidPart::Type::Triangle;
    if (triangle) ends[0] = heldAt(pc, 0), ends[1] = heldAt(pc, 1);
    const int m = gapModel ? bodyGap(f, pc.cp, bodies[pc.body], pc.part, dt, params_.margin + projected, params_.rule, c,
                                     &tangent_, held, triangle ? ends : nullptr)
                           : cpBodyContact(f, bounds_[pc.cp], pc.cp, bodies[pc.body], pc.part, dt, params_.margin,
                                           params_.rule, c[0]);
    for (int q = 0; q < m; ++q) {
      c[q].body = pc.body;
      bodyContacts_.push_back(c[q]);
    }
  }
}

Real CollisionStage::bodyOverlap(Fabric& f, int k) {
  // A query: refit turns the section frames to the current tangents, which changes the next step's
  // frames (they follow their previous direction): put them back so that asking changes nothing.
  const Vec3Array dirs = f.secDir;
  const ThreadCountScope threadCount(params_.threads);
  refit(f, 0);
  const RigidBody& b = bodies.at(k);
  Real worst = -INFINITY;
  BodyContact c[2];
  const auto measure = [&](std::size_t part, Index e) {
    const int m = params_.model == ContactModel::Gap
                      ? bodyGap(f, e, b, static_cast<int>(part), 0, params_.margin, params_.rule, c)
                      : cpBodyContact(f, bounds_[e], e, b, static_cast<int>(part), 0, params_.margin, params_.rule, c[0]);
    for (int q = 0; q < m; ++q) worst = std::max(worst, -c[q].gap);
  };
  if (b.parts.size() >= BodyCollider::kTreeParts) {
    // A mesh: only the parts whose boxes meet a CP's bound (which holds its sections) are measured,
    // through the body's bound tree (all pairs of a 2 000-triangle bullet and a ply were 2 s).
    PartTree tree;
    tree.build(b);
    const Mat3 R = b.ori.toRotationMatrix();
    std::vector<int> parts;
    for (Index e = 0; e < f.nElems(); ++e) {
      if (!f.alive[e]) continue;
      const Vec3 centre = R.transpose() * (bounds_[e].centre - b.pos);
      const Vec3 half = R.transpose().cwiseAbs() * aabbHalf(bounds_[e]) + Vec3::Constant(params_.margin);
      parts.clear();
      tree.query(centre - half, centre + half, parts);
      for (int part : parts) measure(static_cast<std::size_t>(part), e);
    }
  } else {
    for (std::size_t part = 0; part < b.parts.size(); ++part)
      for (Index e = 0; e < f.nElems(); ++e)
        if (f.alive[e]) measure(part, e);
  }
  f.secDir = dirs;
  return worst;
}

}  // namespace woven
