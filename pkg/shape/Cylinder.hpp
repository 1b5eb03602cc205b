// A cylinder part (RigidPart::Type::Cylinder) in its own frame: axis z, centre at the origin,
// radius R, half-length H. With a chisel nose (chiselAngle alpha > 0) it is cut by two flats
//     +-x <= w + (H - z) tan(alpha)      (w = landHalfWidth < R)
// that leave a flat tip of half-width w on the nose face z = H and meet the round surface at
// z = H - (R - w) / tan(alpha): the fragment-simulating projectile's nose (docs/ballistic.md, "Packs
// and standard projectiles"). Convex either way, so its gap to a CP's section along a direction n is
// the separating-plane form of the box (geom/GapFunction: min over the part of y.n minus the
// section's reach), and that needs the part only through cylinderMinAlong, exact here.
#pragma once
#include "core/Types.hpp"
#include "shape/RigidBody.hpp"

namespace woven {

/// Throws ParameterError naming the field: half length, chisel angle, land half-width (the flats
/// must end on the round surface before the tail: (R - w) / tan(alpha) < 2H).
void validateCylinder(const RigidPart& p);

/// min over the part of y.n [m], n a unit vector in the part frame. Exact: the minimum of a linear
/// function over this convex solid lies on one of its edge curves (the tail rim, the nose rim's two
/// arcs, the flats' elliptic arcs on the round surface, the land's corners), each minimised in
/// closed form.
Real cylinderMinAlong(const RigidPart& p, const Vec3& n);

/// Directions (unit, part frame, from the point q towards the part) that a separating plane of the
/// part and a section at q may take: the faces' normals (nose and tail faces, the flats), the
/// round surface's normal at q's azimuth, and the direction to q's closest point on the round
/// cylinder (exact for the round cylinder; the chisel's faces are among the normals). Returns the
/// count (at most 6).
int cylinderDirections(const RigidPart& p, const Vec3& q, Vec3 out[6]);

}  // namespace woven
