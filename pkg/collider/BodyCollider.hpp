// Collider between the CPs and the parts of rigid bodies (a projectile, clamps): the broad phase of
// the body contacts. Few parts against many CPs, so a flat list per part with its own Verlet skin:
// the CPs whose broad-phase box (grown by their motion in the step) lies within `skin` of the part's
// box are listed, and the list holds until the body and the fastest CP together have travelled the
// skin since it was made (measured from the step's growths: O(CPs) compares, no box tests).
// A body of many parts (a mesh of thousands of triangles) has a bound tree of its parts' boxes in its
// own frame, built once (they are fixed in it): a list costs the CPs near the body times the depth,
// and the parts near the fabric, not all of them.
#pragma once
#include "bound/OBB.hpp"
#include "fabric/Fabric.hpp"
#include "shape/RigidBody.hpp"
#include <vector>

namespace woven {

struct BodyCandidate {
  Index cp;
  int body, part;
};

/// Bound tree of a rigid body's parts: axis-aligned boxes in the body frame, split at the median of
/// the longest axis down to a few parts a leaf. Built once per body (its parts are fixed in it).
class PartTree {
 public:
  void build(const RigidBody& b);
  /// Parts whose box meets the box [lo, hi] (body frame) into `out` (appended, in tree order).
  void query(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const;
  Vec3 rootLo() const { return nodes_.empty() ? Vec3::Zero() : nodes_[0].lo; }
  Vec3 rootHi() const { return nodes_.empty() ? Vec3::Zero() : nodes_[0].hi; }
  Real reach = 0;       ///< farthest point of any part from the body's centre [m]
  long id = -1;         ///< the body it was built for (its YADE id and part count)
  std::size_t parts = 0;

 private:
  struct Node {
    Vec3 lo, hi;
    int first = 0, count = 0;  // a leaf's range of order_ (count 0: an inner node)
    int left = -1, right = -1;  // an inner node's children
  };
  int split(int first, int count, const std::vector<Vec3>& lo, const std::vector<Vec3>& hi);
  std::vector<Node> nodes_;
  std::vector<int> order_;
};

class BodyCollider {
 public:
  static constexpr std::size_t kTreeParts = 16;  ///< bodies with at least this many parts use a PartTree
  Real skin = 1e-4;  ///< [m] > 0

  /// Candidate (CP, body, part) triples into `out`, sorted by body, part, CP. `grown` are the CPs'
  /// broad-phase boxes, `grow` how far each CP can move in the step [m], dt the step [s].
  void collide(const Fabric& f, const std::vector<OBB>& grown, const std::vector<Real>& grow,
               const std::vector<RigidBody>& bodies, Real dt, std::vector<BodyCandidate>& out);
  long rebuilds = 0;  ///< lists made since the start

 private:
  std::vector<BodyCandidate> list_;
  std::vector<PartTree> trees_;  // by body index (used for bodies of kTreeParts parts or more)
  std::vector<int> hits_;
  std::vector<std::pair<int, Index>> found_;
  Real travelled_ = 0;   // body + fastest CP travel since the list was made [m]
  std::size_t layout_ = 0;
  bool valid_ = false;
};

/// Axis-aligned half-widths of an OBB [m].
inline Vec3 aabbHalf(const OBB& b) { return b.axes.cwiseAbs() * b.extent; }

}  // namespace woven
