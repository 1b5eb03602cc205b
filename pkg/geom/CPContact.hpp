// Geometry functor: the contact between two CPs from their OBBs (the bound functor's boxes, which
// carry the margin), static at the start of the step or, failing that, moving over the step.
#pragma once
#include <limits>
#include "bound/OBB.hpp"
#include "fabric/Fabric.hpp"
#include "shape/Section.hpp"
#include <vector>

namespace woven {

/// Normals closer than 45 degrees to either CP's axis are not taken as the TD of a yarn contact
/// (see obbContact's lateralCos): between pieces of yarn the contact pushes across the yarns, and
/// the box corners of two chains would otherwise push yarns along themselves.
constexpr Real kLateralCos = 0.70710678118654752;

enum class SectionLine : std::uint8_t {
  Hit,       ///< the line meets the section: lambda is set
  Beside,    ///< the line passes beside the section, or beyond the CP's ends: the CP's body is not on it
  Axial,     ///< the line runs along the CP (|m.t| > kLateralCos): no section answer
};
/// Where the elliptic cylinder of CP e ends along the line p + lambda m (m unit): the largest lambda
/// [m] with p + lambda m inside the CP's section at p's place along the CP (end sections
/// interpolated linearly; within a tenth of the CP beyond an end, the end section).
SectionLine sectionSurfaceAlong(const Fabric& f, Index e, const Vec3& p, const Vec3& m, SectionRule rule, Real& lambda);

/// Which gap function measured a contact (geom/GapFunction.hpp): the paper's box normal with the
/// depth on the sections (contact model `paper`), the gap model's crossing / side-by-side forms of
/// a CP pair, or a persistent crossing of two yarns (engine/CrossingContacts: the points are its
/// sliding coordinates, held for the step).
enum class ContactKind : std::uint8_t { Paper = 0, Cross = 1, Side = 2, Crossing = 3 };

/// A side-by-side point (geom/GapFunction.hpp): an end of A's axis with the closest point of B to it
/// (A), an end of B's axis with the closest point of A to it (B), or the axes' closest approach
/// (Closest). Each is a vertex-segment or segment-segment distance: the point slides with the pieces
/// and the gap does not change by the sliding itself.
enum class SideAnchor : std::uint8_t { A = 0, B = 1, Closest = 2 };

struct CPContact {
  Index cpA = -1, cpB = -1;      ///< CPs, cpA < cpB
  Vec3 normal = Vec3::UnitZ();   ///< unit, from A towards B
  /// Separation of the two elliptic cylinders along `normal` at the contact point [m]: on the line
  /// through the point along the normal, B's surface minus A's; < 0 is a penetration (flattened away
  /// or, past the MCD, a residual overlap). For a contact found by the moving test, the distance
  /// closed before the first time of contact plus 2 margin.
  Real gap = 0;
  Real boxDepth = 0;             ///< the boxes' TD depth [m] (includes both margins)
  bool sectional = false;        ///< the gap was measured on both sections (not the boxes' own)
  Vec3 point = Vec3::Zero();     ///< contact point [m]: between the CP axes' closest points (static), clipped centroid (moving)
  Real sA = 0.5, sB = 0.5;       ///< where the point lies along each CP, in [0, 1] (weight of its 2nd node)
  Real time = 0;                 ///< first time of contact within the step [s] (0: touching at the start)
  ContactKind kind = ContactKind::Paper;
  Real hA = 0, hB = 0;           ///< gap model: the sections' supports at the point, held for the step [m]
  /// Gap model: the largest hA + hB the pair's sections may claim (GapFunction.hpp, "measure
  /// memory"); +inf for a pair measured for the first time [m].
  Real hCap = std::numeric_limits<Real>::infinity();
  /// Gap model: how far the cap holds the sections' own measure down (their hA + hB less the
  /// capped one, >= 0) [m]. The sections must flatten this much before the capped measure gives.
  Real hHeld = 0;
  Vec3 hDir = Vec3::UnitZ();     ///< gap model: the direction they are measured (and flattened) along (GapFunction.hpp)
  /// Gap model, side by side: which material point the contact holds as the pieces slide (remeasure).
  SideAnchor anchor = SideAnchor::A;
  /// Kind Crossing: the persistent crossing it measures (engine/CrossingContacts), else -1.
  Index crossing = -1;
  /// Kind Crossing: its lines' node weights at its places, fixed for the step (A's first, as
  /// GapFunction's contactStencil gives them: A's negative): nStencil nodes, nStencilA of them A's.
  std::int8_t nStencil = 0, nStencilA = 0;
  Index stencilNode[6] = {0, 0, 0, 0, 0, 0};
  Real stencilW[6] = {0, 0, 0, 0, 0, 0};
  /// Normal impulse its row starts from [N s] (a persistent crossing's last one: warm start).
  Real warm = 0;
  /// Gap its row holds back beyond `gap` [m] >= 0: a persistent crossing's distance lost as its
  /// places moved to the closest points of this step (they move with the lines' shape, and the
  /// distance at the new ones is the smaller), which the next step's tracking will lose again.
  Real drift = 0;
};

/// Static contact of CPs a < b: true (and `out`) when their boxes overlap. The boxes give the normal
/// (paper Sec. 4.3); the depth is measured on the elliptic cylinders along the line in that
/// direction through the midpoint of the closest points of the two CP axes (where two yarn pieces
/// press deepest); when that line passes beside a section the pieces only touch there (gap =
/// 2 margin), and when it runs along a CP (end-on contacts) the boxes' own depth is taken. A
/// box fills the thin edges of a flat ellipse: around a crossing the boxes of neighbouring CPs
/// overlap where the yarns do not (measured on KM2 706: 0.1 mm of false overlap, every section
/// locked at the MCD).
bool cpContactStatic(const Fabric& f, const std::vector<OBB>& bounds, Index a, Index b, Real margin, SectionRule rule,
                     CPContact& out);

/// Moving contact of CPs a < b whose boxes do not overlap at the start: each box translates with
/// the velocity (Fabric::vel) of one of its CP's two nodes over [0, dt] (the four pairings bracket a
/// turning CP); true when they meet within it, at the earliest time (Eberly's moving SAT).
bool cpContactMoving(const Fabric& f, const std::vector<OBB>& bounds, Index a, Index b, Real dt, Real margin,
                     CPContact& out);

/// Position of point p along CP e as the weight of its second node, clamped to [0, 1].
inline Real alongCP(const Fabric& f, Index e, const Vec3& p) {
  const Vec3& x0 = f.pos[f.elem0[e]];
  const Vec3 d = f.pos[f.elem0[e] + 1] - x0;
  const Real s = (p - x0).dot(d) / d.squaredNorm();
  return s < 0 ? 0.0 : (s > 1 ? 1.0 : s);
}

}  // namespace woven
