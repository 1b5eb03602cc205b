// Bound functor: the OBB of every CP (paper Sec. 4.1), refitted each step from the node positions and
// the elliptic sections. A0 runs along the CP, A2 along the mean minor axis of its two end sections,
// A1 = A2 x A0; each extent is the exact support of the convex hull of the two end ellipses along
// that axis (so the box encloses the elliptic cylinder and touches it), plus `margin`.
#pragma once
#include "bound/OBB.hpp"
#include "fabric/Fabric.hpp"
#include "shape/Section.hpp"
#include <vector>

namespace woven {

/// Unit tangent of every node (central difference of its neighbours; the end element at yarn ends)
/// into `tangent`, and Fabric::secDir made unit and normal to it (the section turns with the yarn).
void updateSectionFrames(Fabric& f, Vec3Array& tangent);

/// OBB of CP e with its sections as they are, enlarged by margin [m] on every side.
OBB cpBound(const Fabric& f, const Vec3Array& tangent, Index e, SectionRule rule, Real margin);

/// cpBound of every CP into boxes (resized to the CP count).
void refitBounds(const Fabric& f, const Vec3Array& tangent, SectionRule rule, Real margin, std::vector<OBB>& boxes);

}  // namespace woven
