// Bound functor: the OBB of every CP (paper Sec. 4.1), refitted each step from the node positions and
// the elliptic sections. A0 runs along the CP, A2 along the mean minor axis of its two end sections,
// A1 = A2 x A0; each extent is the exact support of the convex hull of the two end ellipses along
// that axis (so the box encloses the elliptic cylinder and touches it), plus `margin`.
#pragma once
#include "bound/OBB.hpp"
#include "fabric/Fabric.hpp"
#include "shape/Section.hpp"
#include <algorithm>
#include <vector>

namespace woven {

/// Unit tangent of the yarn at node k: the central difference of its neighbours, or its one live
/// element at a yarn end or beside a broken element (whose far node, flying off with the other
/// piece, says nothing about this one's direction).
inline Vec3 yarnTangentAt(const Fabric& f, Index k) {
  const Yarn& y = f.yarns[f.nodeYarn[k]];
  const Index local = k - y.firstNode;
  const bool before = local > 0 && f.alive[y.firstElem + local - 1];
  const bool after = local < y.nElems && f.alive[y.firstElem + local];
  const Index a = before || !after ? std::max(k - 1, y.firstNode) : k;
  const Index b = after || !before ? std::min(k + 1, y.firstNode + y.nNodes - 1) : k;
  return (f.pos[b] - f.pos[a]).normalized();
}

/// Unit tangent of node k (yarnTangentAt) into tangent[k], and Fabric::secDir[k] made unit and
/// normal to it (the section turns with the yarn).
inline void turnSectionFrame(Fabric& f, Index k, Vec3Array& tangent) {
  const Vec3 t = yarnTangentAt(f, k);
  tangent[k] = t;
  Vec3 d = f.secDir[k] - f.secDir[k].dot(t) * t;
  const Real len = d.norm();
  f.secDir[k] = len > 1e-6 ? Vec3(d / len) : t.unitOrthogonal();
}

/// turnSectionFrame of every node (`tangent` resized to the node count).
void updateSectionFrames(Fabric& f, Vec3Array& tangent);

/// OBB of CP e with its sections as they are, enlarged by margin [m] on every side.
OBB cpBound(const Fabric& f, const Vec3Array& tangent, Index e, SectionRule rule, Real margin);

/// cpBound of every CP into boxes (resized to the CP count).
void refitBounds(const Fabric& f, const Vec3Array& tangent, SectionRule rule, Real margin, std::vector<OBB>& boxes);

}  // namespace woven
