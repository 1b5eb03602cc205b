// First half of the paper's response (Sec. 5.1 steps 1-3, Sec. 5.2.2): while a node's deformation
// eps is below the MCD, a penetration is taken up by flattening the sections of both CPs along the
// contact normal, with no velocity change (the forces that redistribute filaments are negligible).
// A section that is still circular turns its minor axis to the normal; a flattened one flattens
// further only along its own minor axis (within 45 degrees of the normal). Sections keep their shape
// after the contact ends: filaments that moved stay where they went (no restoring force in the model).
#pragma once
#include "fabric/Fabric.hpp"
#include "law/ContactParams.hpp"

namespace woven {

/// Direction `dir` along which node k's section flattens for contact normal n, and the cosine
/// |n.dir| it does so with; 0 when it cannot (n within 45 degrees of the yarn, or across a section
/// already flattened another way).
Real flatteningDirection(const Fabric& f, const Vec3Array& tangent, Index k, const Vec3& n, Vec3& dir);

/// How much CP e's extent along n can still shrink by flattening its end sections before the MCD
/// locks them [m]. The extent is the larger reach |(x_k - centre).n| + support_k(n) of the two end
/// sections, so it is that reach minus the larger of the two reaches at the MCD.
/// `flat` (every node's eps) defaults to Fabric::secFlat.
Real flatteningCapacity(const Fabric& f, const Vec3Array& tangent, Index e, const Vec3& n, const ContactParams& p,
                        const std::vector<Real>* flat = nullptr);

/// Flattens the end sections of CP e that reach beyond (extent - delta) along n down to it [m]
/// (b shrinks by the excess / cosine, so eps = 1 - b/r0 grows by excess / (cosine r0), capped at
/// the MCD); an end already within stays as it is. Reaches are measured with `flatBefore` (every
/// node's eps at the start of the pass), so several contacts of one node ask for the same
/// flattening without adding it up. The direction each contact flattens a node along is added to
/// dirSum[k], weighted by the deformation it asks for: turnSections() then sets the minor axis.
void flattenCP(Fabric& f, const Vec3Array& tangent, Index e, const Vec3& n, Real delta, const ContactParams& p,
               const std::vector<Real>& flatBefore, Vec3Array& dirSum);

/// Contact model `gap` (geom/GapFunction.hpp): the gap is measured at the point s along CP e, so
/// the flattening is too. What the section at s can still lose before the MCD locks the end
/// sections [m]: (1 - s) and s times the two nodes' capacities, each the loss of its support along
/// n or, with `thickness` (crossing contacts, which measure the half-thickness b), of b itself.
Real flatteningCapacityAt(const Fabric& f, const Vec3Array& tangent, Index e, Real s, const Vec3& n, bool thickness,
                          const ContactParams& p, const std::vector<Real>* flat = nullptr);
/// Flattens the end sections of CP e so that the section at s loses delta [m] (as measured by
/// flatteningCapacityAt): each node gives the fraction delta / capacity of what it has left,
/// measured with `flatBefore`; the minor axes turn towards n through dirSum as in flattenCP.
void flattenAt(Fabric& f, const Vec3Array& tangent, Index e, Real s, const Vec3& n, bool thickness, Real delta,
               const ContactParams& p, const std::vector<Real>& flatBefore, Vec3Array& dirSum);

/// After a pass of flattenCP: each touched node's minor axis becomes the mean of its old axis
/// (weighted by its eps before the pass) and the directions its contacts flattened it along
/// (weighted by the deformation each asked for), made normal to the yarn. A node pressed by several
/// contacts (the four CP pairs around a crossing) thus flattens along their mean normal, not along
/// whichever came first. dirSum is zeroed again.
void turnSections(Fabric& f, const Vec3Array& tangent, const std::vector<Real>& flatBefore, Vec3Array& dirSum);

}  // namespace woven
