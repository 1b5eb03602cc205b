// Separating-axis test for two oriented boxes (paper Sec. 4.2-4.4; Eberly, "Intersection of Convex
// Objects: The Method of Separating Axes" and "Dynamic Collision Detection using Oriented Bounding
// Boxes"; Gottschalk et al., OBBTree). The 15 candidate axes are the 3 face normals of each box and
// the 9 cross products A_i x B_j; the boxes are disjoint iff the projections on one of them do not
// overlap (early out on the first such axis).
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
/// the minimum over the 15 axes (edge axes with |A_i x B_j| < kParallel are left out of the minimum:
/// their face axes bound the same overlap).
struct BoxContact {
  bool overlap = false;
  Vec3 normal = Vec3::UnitX();  ///< unit, from A towards B
  Real depth = 0;               ///< [m], >= -slop
  int axis = -1;                ///< 0-2 face of A, 3-5 face of B, 6 + 3i + j edge A_i x B_j
  int nPoints = 0;
  std::array<BoxContactPoint, 8> points;
};

/// Relative tolerance added to |A_i . B_j| in the separation test, so that nearly parallel edges
/// (A_i x B_j ~ 0) never report a false separation through rounding (Gottschalk's epsilon).
constexpr Real kAxisEpsilon = 1e-12;
/// Edge axes shorter than this (sine of the angle between the edges) take no part in the depth.
constexpr Real kParallel = 1e-6;

/// Yes/no overlap with early out on the first separating axis.
bool obbOverlap(const OBB& a, const OBB& b);
/// Overlap test with the TD vector and the contact points (face-face polygon clipping, edge-edge
/// closest points; a vertex-face contact is the one-point case of the clipping). Boxes separated by
/// at most `slop` [m] along every axis count as touching (depth in [-slop, 0]).
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
