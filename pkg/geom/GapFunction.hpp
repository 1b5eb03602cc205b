// Gap functions of the contact model `gap` (docs/collisions.md, "Gap functions"): for each contact
// kind, one scalar g(x) of the node positions (and of a body's pose), < 0 an overlap, together with
// its gradient, which is the impulse row (law/ImpulseLaw) and the direction of the position
// projection (law/PositionProjection). Measure, solve and project thus act on one function: the
// paper's response measured the overlap on one line and pushed along another, and at tilted,
// sliding crossings the difference ratcheted the yarns into each other (docs/collisions.md).
//
// Within a step the section state (semi-axes, minor-axis direction: state variables that the
// flattening passes change between measurements) is held fixed: it is a parameter of g, not a
// function of the positions. The kinds:
//   Cross  crossing CPs: g = |B(t*) - A(s*)| - h_A - h_B, (s*, t*) the closest points of the two
//          axis segments, n the unit vector between them and h_X X's section measure at the point:
//          its half-thickness b where the yarns cross at 45 degrees or more (and within one yarn:
//          a fold lies face to face), its support along the normal (made normal to the yarn) below
//          20 degrees, blended between (docs/collisions.md says why). By the envelope theorem
//          dg/dx_k = w_k n with w = -(1-s*), -s*, 1-t*, t*.
//   Side   side-by-side (near-parallel) CPs, two points at the ends of the part of A that lies
//          alongside B, each held by the segment end that makes it (SideAnchor): an end of A with
//          B's closest point to it, or an end of B with A's closest point to it. The same g and,
//          by the envelope theorem, the same gradient form: a line contact as a two-point manifold
//          of vertex-segment distances, which the pieces' sliding along each other leaves unchanged.
//          Skew pieces whose axes come closest inside the shared part (an X at a small angle): that
//          closest point (s*, t*), which moves along with them, replaces the farther end.
// Measure memory (capMeasure): the sections' measure h_A + h_B is a state (their turn, flattening
// and the crossing angle), not moved by forces; between steps it may grow only into room the axes
// leave, never into an overlap (a pair new to the broad phase, or a point far from the last step's,
// claims its half-thicknesses at most), and a body contact's sections likewise. What the cap holds
// back (CPContact::hHeld, BodyContact::held) must flatten first (a projectile flattens the sections
// it presses as a yarn does, paper Sec. 5.1), and held sections are not counted on to flatten.
// Without it, kinked chains after breaks turned sections' widths onto their neighbours by 200 um a
// step and the projection pushed on phantom overlaps.
//   Sphere a CP and a sphere part of centre c, radius R: g = |c - P| - R, P the closest point to c
//          of the CP's elliptic section at s* (c's place along the axis); n = (c - P)/|c - P| is the
//          ellipse's surface normal at P; beyond an end of the CP, within the section's outline, P
//          is on the flat end face. dg/dx_k = -w_k n, dg/dc = n (body rows: v + w x (c - x_G));
//          on an end face the turn of the axis is left out of the row. Where an end node's section
//          (a circle of its half-thickness) leaves less gap than the section at s*, a second
//          contact holds that node (s = 0 or 1 kept): a CP along the sphere meets it at its
//          thickest section, not at c's place.
//   Box    a CP and a box part, n the separating-axis normal of the two boxes (held for the step):
//          one contact per end section k: g_k = min over the box of y.n - (x_k.n + support_k(n)),
//          the box's lowest point along n minus the section's deepest point; n the box face normal
//          (of 6) that leaves the CP the most room (the separating-axis choice among the box's
//          faces; it turns with the box), the supports held. dg_k/dx_k = -n, dg_k/dbody = n at the
//          arm x_k + support_k n - x_G (translation and rotation).
//   Cylinder a CP and a cylinder part (the RCC; the FSP's chisel-nosed one: shape/Cylinder.hpp): the
//          box's separating-plane form, one contact per end section k, each with its own n_k (held in
//          the part frame): of the candidate directions (the faces' normals, the round surface's at
//          the node, the direction to the round cylinder's closest point) the one that leaves the
//          section the most room; g_k = min over the part of y.n_k (exact) - (x_k.n_k + support_k);
//          the same rows as the box.
//   Crossing a persistent crossing of two yarns (engine/CrossingContacts): g = |C_B(t) - C_A(s)|
//          - h_A - h_B between the yarns' smooth lines (geom/YarnCurve.hpp: the chains with their
//          corners rounded over a short blend), at the crossing's sliding coordinates (s, t):
//          state, held for the step and moved between steps to the lines' closest points. At rest
//          they lie at a crossing node of each yarn. For fixed (s, t), dg/dx_k = w_k n exactly,
//          w the lines' node weights (contactStencil: two or three nodes a yarn, a convex
//          combination); and since (s, t) are the closest points, moving them to the next step's
//          changes g only to second order (the envelope theorem), where the kinked chords'
//          distance turns by the crimp angle as a point passes a node. One contact stands for the
//          crossing where four chord pairs' contacts did, each about 16 um off the node (the
//          minimum over the kinked chords, which jumped between them; the rounded lines read it to
//          within 1 % of the thickness at a built crossing). It keeps its side at any (s, t) and
//          measures the half-thicknesses (it lives above 45 degrees).
// A pair of CPs is Cross or Side by the angle between the axes with hysteresis (enter Side below
// kSideEnterDeg, leave above kSideLeaveDeg), never by the instantaneous normal. Orientation: a pair
// remembers its normal, and where the axes have passed through each other (the vector between the
// closest points turned against it) g is -|B - A| - h_A - h_B along the remembered side, so a yarn
// pushed through another is pulled back, not pushed on.
#pragma once
#include "fabric/Fabric.hpp"
#include "geom/BodyContact.hpp"
#include "geom/CPContact.hpp"
#include "geom/SegmentDistance.hpp"
#include "shape/RigidBody.hpp"
#include "shape/Section.hpp"

namespace woven {

constexpr Real kSideEnterDeg = 20;  ///< a pair whose axes are closer than this in angle becomes Side [deg]
constexpr Real kSideLeaveDeg = 30;  ///< ... and stays Side until they part by more than this [deg]

/// CP e's section at s in [0, 1]: centre on the axis, tangent t, major axis u, minor axis d (unit,
/// normal to t; end directions interpolated with the same sign), semi-axes interpolated linearly.
struct SectionAt {
  Vec3 centre, t, u, d;
  Real a, b;
};
/// `chord` (may be null: computed) is the unit chord of e at the current positions (ChordFrames).
SectionAt sectionAt(const Fabric& f, Index e, Real s, SectionRule rule, const Vec3* chord = nullptr);
/// sectionAt's minor axis d alone (`chord`: e's unit chord, which d is made normal to).
Vec3 sectionDir(const Fabric& f, Index e, Real s, const Vec3& chord);
/// sectionAt's semi-axes alone (a, b) [m]: each node's, interpolated linearly.
inline SemiAxes semiAxesAt(const Fabric& f, Index e, Real s, SectionRule rule) {
  const Index i = f.elem0[e], j = i + 1;
  const SemiAxes si = semiAxes(f.secRadius[i], f.secFlat[i], rule), sj = semiAxes(f.secRadius[j], f.secFlat[j], rule);
  return {(1 - s) * si.a + s * sj.a, (1 - s) * si.b + s * sj.b};
}

/// Each CP's unit chord, (x_{i+1} - x_i) / |x_{i+1} - x_i|, and its length, taken once per narrow
/// phase for the pairs that share the CP (each CP is in about four pairs): the same expressions, so
/// the same bits, as computing them pair by pair. Valid only while no node moves.
struct ChordFrames {
  Vec3Array unit;
  std::vector<Real> length;
};

/// Side (true) or Cross for CPs a, b, with hysteresis: `wasSide` is the pair's kind at its last
/// measurement. `chords` may be null (computed).
bool sideBySide(const Fabric& f, Index a, Index b, bool wasSide, const ChordFrames* chords = nullptr);

/// The contacts of the pair a < b as the kind says (1 for Cross, 1 or 2 for Side), in out[]: normal,
/// gap (sections measured now), sA/sB, point, kind, hA/hB. `orient` (may be null) points to the
/// pair's two remembered normals, one per point (a side-by-side pair's points lie at the two ends
/// of the shared part, where skew axes can have opposite normals; one point reads orient[0]). `tangent` (may be null: computed) holds every node's yarn tangent
/// (bound/CPBound's yarnTangentAt, as the stage's refit leaves them). `closest` (may be null:
/// computed) holds the axes' closest points, closestSegmentSegment of the pair's four nodes, where
/// the caller has them. `chords` (may be null: computed) holds the CPs' unit chords at the current
/// positions. Returns the count.
int pairGaps(const Fabric& f, Index a, Index b, bool side, SectionRule rule, const Vec3* orient, CPContact out[2],
             const Vec3Array* tangent = nullptr, const SegmentClosest* closest = nullptr,
             const ChordFrames* chords = nullptr);

/// The measure memory: the sections' measure hA + hB of a CP pair may grow between steps only into
/// room that is there (up to the axes' distance r), never into an overlap: it is capped at
/// max(`remembered`, r), `remembered` the pair's measure at its last narrow phase, and the cap is
/// kept in c.hCap for later measurements of the step (after flattening). The measure is a state
/// of the sections (their turn, flattening and the crossing angle), which the model does not move
/// by forces: when the yarns kink (a broken end whipping) it turned a section's width onto its
/// neighbour by 200 um in one step while the axes moved apart, and the projection then pushed
/// the pair apart with energy no force had given. A section that would turn into its neighbour is
/// held by it (the rows and the projection still act on g = r - hA - hB, with the capped measure).
void capMeasure(CPContact& c, Real remembered);

/// The persistent crossing's contact (kind Crossing): the curves' points on CP a at s and CP b at t
/// (a < b; held for the step), the normal kept on `orient`'s side, the half-thicknesses there as
/// the sections' measure (uncapped: capMeasure applies the crossing's memory after).
void crossingGap(const Fabric& f, Index a, Real s, Index b, Real t, SectionRule rule, const Vec3& orient,
                 CPContact& out);

/// Most nodes a contact's gap reads: a persistent crossing's two lines, three nodes each.
constexpr int kMaxStencil = 6;
/// The nodes of contact c's gap and their weights: dg/dx_k = w_k n (A's negative, B's positive).
/// A CP pair: its four nodes with the barycentric weights (1 - sA, sA, 1 - sB, sB); a persistent
/// crossing: the two lines' weights (YarnCurve.hpp), two or three nodes each, as crossingGap kept
/// them in the contact. Returns the count.
int contactStencil(const Fabric& f, const CPContact& c, Index node[kMaxStencil], Real w[kMaxStencil]);

/// Measures contact c again at the current positions: closest points (Cross, and a Side pair's
/// closest-approach point), B's closest point to the fixed A(sA) or A's closest point to the fixed
/// B(sB) (a Side end, by its anchor), normal kept on c's side, and the gap with c's section supports
/// hA, hB (held) or, with `sections`, supports measured again (after flattening). This is g(x).
void remeasure(const Fabric& f, CPContact& c, SectionRule rule, bool sections, const Vec3Array* tangent = nullptr);

/// CP-body contacts of the gap model in out[] (the sphere form: 1, or 2 with an end node's; the box
/// and cylinder forms: one per end section
/// that can touch), each listed when g <= margin + dt (the body's speed at the point + the CP's
/// fastest node): a speculative contact, whose row lets the pair close exactly its gap.
/// `held` (may be null) is the same CP and part's contact of the last step: the sections' measure
/// may grow only into room (capMeasure's rule; without one, the half-thickness is the reference).
/// A triangle's contacts at an end node over its face (BodyContact::end 0 or 1) each keep their own
/// memory: `heldEnds` (may be null, or either entry) the last step's at end 0 and 1, `held` its
/// edge contact's. Returns the count.
int bodyGap(const Fabric& f, Index cp, const RigidBody& body, int part, Real dt, Real margin, SectionRule rule,
            BodyContact out[2], const Vec3Array* tangent = nullptr, const BodyContact* held = nullptr,
            const BodyContact* const* heldEnds = nullptr);

/// Measures body contact c again at the current positions and pose (its normal held for a box, its
/// section frame held for a sphere): g(x, body pose). Sets gap, point, s and normal (sphere).
void remeasureBody(const Fabric& f, const RigidBody& body, BodyContact& c);

/// Closest point of the ellipse (x/a)^2 + (y/b)^2 = 1 to (px, py) (Eberly, "Distance from a point to
/// an ellipse", robust bisection on the root of F(t)); its coordinates in qx, qy. Returns true when
/// the point lies outside (or on) the ellipse.
bool closestOnEllipse(Real a, Real b, Real px, Real py, Real& qx, Real& qy);

}  // namespace woven
