// A yarn's smooth centre line, for the persistent crossings (engine/CrossingContacts): the chain of
// chords with each inner node's corner rounded over a short blend. Around node k a quadratic Bezier
// arc runs from the point lambda_k before the node on the CP before it to the point lambda_k after
// it on the CP after it, with the node as its middle control point,
//     B(u) = (1 - u)^2 P_a + 2 u (1 - u) x_k + u^2 P_b,   u in [0, 1] (1/2 at the node),
// tangent to both chords where it meets them (so the line is C1); elsewhere the line is the chord.
// lambda_k = min(kBlend r0_k, kBlendMax l0) is fixed (rest lengths and section radius), so every point
// is a fixed convex combination of at most three nodes (yarnCurveWeights), and the line is the yarn's
// own chain to within lambda sin(phi / 2) / 2 of a node whose chords turn by phi (1.4 um at a built
// KM2 706 crossing; the chords' own closest approach lies 16 um off the node, 2 % of the thickness
// closer).
// Why a smooth line: at a crossing node the kinked chords come closest about 16 um off the node on
// one of four chord pairs, and the closest pair jumps as the yarns move; on the rounded lines the
// closest points lie at the node at rest and move smoothly as the yarns slide, so a crossing's
// sliding coordinates follow them (closestStep) and its gap is measured on them
// (geom/GapFunction.hpp, Crossing).
#pragma once
#include "fabric/Fabric.hpp"

namespace woven {

/// A material place on a yarn: CP `cp` at s in [0, 1] (the weight of its second node).
struct YarnPlace {
  Index cp = -1;
  Real s = 0;
};

/// Each inner node's corner is rounded over kBlend times its section's rest radius along each chord
/// (20 um in KM2 706: the quadrant points of a built crossing, 16 um off the node, lie within it, so
/// its curves come closest at the node), at most kBlendMax of the shorter CP.
constexpr Real kBlend = 0.25, kBlendMax = 0.4;

/// The line on CP e at s: position and its first and second derivatives in s.
struct CurvePoint {
  Vec3 x, d1, d2;
};
CurvePoint yarnCurveAt(const Fabric& f, Index e, Real s);

/// The line on CP e at s as weights of the nodes: C(s) = sum_k w[k] x_{node[k]}, w[k] >= 0, summing
/// to 1 (the CP's two nodes, and in a rounded corner the node across it); zero weights are left out.
/// Returns the count (at most 3). A convex combination: the point moves no faster, and no farther,
/// than the fastest node of its CP and its neighbours.
int yarnCurveWeights(const Fabric& f, Index e, Real s, Index node[3], Real w[3]);

/// Moves `p` by ds (in CP fractions of p.cp) along its yarn: a place passing a node carries the rest
/// of its move over into the next CP in proportion to the rest lengths. Returns false, leaving p
/// at the yarn's end, when the move would leave the yarn.
bool walkAlong(const Fabric& f, YarnPlace& p, Real ds);

/// closestStep's answers when it makes no step: the closest points are not defined there (the
/// lines run parallel, or curve more than they cross), or a place would leave its yarn.
constexpr Real kNoStep = -1, kLeftYarn = -2;

/// One Newton step of the closest points of the two yarns' lines from (a, b) (minimum of
/// |C_B(t) - C_A(s)|^2 / 2), each parameter's step capped at half a CP; the places walk into the
/// neighbouring CPs where they leave theirs. Returns the distance the two places moved along their
/// lines [m] (the step's size), or kNoStep / kLeftYarn (the places then unchanged, or at the end).
/// `distance` (may be null): the lines' distance at the places the step started from [m].
Real closestStep(const Fabric& f, YarnPlace& a, YarnPlace& b, Real* distance = nullptr);

/// closestStep repeated until the places move less than `tol` [m] or `maxSteps` were made. Returns
/// false when a step is undefined, a place leaves its yarn or it did not converge.
bool closestPlaces(const Fabric& f, YarnPlace& a, YarnPlace& b, Real tol, int maxSteps);

/// The canonical form of a place at a node: the CP that starts there (s = 0), except at the yarn's
/// last node (its last CP, s = 1); within a CP the place is kept.
inline void canonical(const Fabric& f, YarnPlace& p) {
  if (!(p.s >= 1)) return;
  const Yarn& y = f.yarns[f.elemYarn[p.cp]];
  if (p.cp + 1 < y.firstElem + y.nElems) ++p.cp, p.s = 0;
}

}  // namespace woven
