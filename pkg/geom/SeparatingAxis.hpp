// Separating-axis test for two oriented boxes (paper Sec. 4.2-4.4; Eberly, "Intersection of Convex
// Objects: The Method of Separating Axes" and "Dynamic Collision Detection using Oriented Bounding
// Boxes"; Gottschalk et al., OBBTree). The 15 candidate axes are the 3 face normals of each box and
// the 9 cross products A_i x B_j; the boxes are disjoint iff the projections on one of them do not
// overlap (early out on the first such axis). Near-parallel edge axes are evaluated on their exact
// cross product, so the answers hold to ~1e-14 of the box size at any angle (SeparatingAxis.cpp;
// tests/cpp/test_sat_oracle.cpp checks them against a __float128 oracle).
#pragma once
#include "bound/OBB.hpp"
#include <array>

namespace woven {

/// One contact point: `onA` lies on A's surface, `onB` on B's surface, depth = (onA - onB).normal >= 0.
struct BoxContactPoint {
  Vec3 onA = Vec3::Zero(), onB = Vec3::Zero();
  Real depth = 0;  ///< [m]
};

/// Result of the static test. When `overlap`, (normal, depth) is the translation distance (TD):
/// moving B by depth*normal (or A by -depth*normal) brings the boxes into touching contact, and it is
/// the minimum over the 15 axes, edge axes normalised (only exactly parallel edges, whose cross
/// product vanishes, are not axes). Every contact point lies on its own box and within |depth| of
/// the other (onA - onB = depth*normal for the single edge-edge point).
struct BoxContact {
  bool overlap = false;
  Vec3 normal = Vec3::UnitX();  ///< unit, from A towards B
  Real depth = 0;               ///< [m], >= -slop (boxes apart by less than the allowance: -slop)
  int axis = -1;                ///< 0-2 face of A, 3-5 face of B, 6 + 3i + j edge A_i x B_j
  int nPoints = 0;
  std::array<BoxContactPoint, 8> points;
};

/// Allowance of the separation test (Gottschalk's epsilon, made a length): boxes apart by at most
/// kAxisEpsilon * (sum of the six half extents) along every unit axis count as touching, so rounding
/// (~1e-14 of the size) never separates touching boxes. On an edge axis it is scaled by |A_i x B_j|
/// like the radii, never divided by it.
constexpr Real kAxisEpsilon = 1e-12;
/// An edge axis A_i x B_j is left out when shorter than this: zero for exactly parallel edges (the
/// face axes then decide, as in 2-D), otherwise only where leaving it out is invisible: it changes
/// the depth of overlapping boxes by a few min(e) |A_i x B_j| (at most 0.16 x size x |A_i x B_j|
/// measured on near-parallel pairs), and |A_i x B_j|^2 stays a normal double. Every other edge axis
/// counts, however near parallel: its cross product is evaluated exactly (SeparatingAxis.cpp).
constexpr Real kParallel = 1e-150;

/// Yes/no overlap with early out on the first separating axis.
bool obbOverlap(const OBB& a, const OBB& b);
/// The same answer, first asking whether `probe` lies inside both boxes: then they overlap (the
/// test's allowance only widens it), with two point-in-box tests instead of the frame and up to 15
/// axes. A point between two touching CPs' axes (closestMidpoint) settles most touching pairs.
inline bool obbOverlap(const OBB& a, const OBB& b, const Vec3& probe) {
  return (a.outside(probe) <= 0 && b.outside(probe) <= 0) || obbOverlap(a, b);
}
/// Overlap test with the TD vector and the contact points (face-face polygon clipping, edge-edge
/// closest points; a vertex-face contact is the one-point case of the clipping; where the edge-edge
/// points are ill-defined, at face/edge ties and near-parallel edges, clipping along the normal).
/// Boxes separated by at most `slop` [m] (plus the allowance kAxisEpsilon) along every axis count as
/// touching (depth in [-slop, 0]).
/// With lateralCos < 1 the TD is the minimum over the axes L with |L.A0| <= lateralCos and
/// |L.B0| <= lateralCos only (when there is one): for pieces of yarn, whose A0 runs along the yarn,
/// this keeps the normal across both yarns; the yes/no answer still uses all 15 axes.
/// With points = false the contact points are not clipped (nPoints = 0): the TD alone.
BoxContact obbContact(const OBB& a, const OBB& b, Real slop = 0, Real lateralCos = 1, bool points = true);

/// Moving test: A and B translate at constant velocities va, vb [m/s] over [0, dt] [s] (no rotation
/// within the step). `hit` when they meet in that interval; `time` is the first time of contact [s]
/// (0 if they overlap at the start) and `contact` the contact at that time.
struct SweptContact {
  bool hit = false;
  Real time = 0;
  BoxContact contact;
};
SweptContact obbFirstContact(const OBB& a, const Vec3& va, const OBB& b, const Vec3& vb, Real dt);

}  // namespace woven
