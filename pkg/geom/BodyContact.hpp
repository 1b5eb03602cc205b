// Geometry functor between a CP and a part of a rigid body (Box or Sphere), static at the start of
// the step or, failing that, moving over it: the body's impulses (law/ImpulseLaw) need the same
// normal, gap, point and weight along the CP as a CP-CP contact.
//   Box part:    the CP's OBB (the bound functor's, with its margin) against the part's box by the
//                separating-axis test (paper Sec. 4.2-4.4: the paper bounds its projectile by an OBB)
//                for the normal; the depth along it from the CP's elliptic end sections;
//                when they are apart at the start, Eberly's moving SAT over the step with the body's
//                velocity at the part centre against either node's velocity (the earliest hit).
//   Sphere part: the closest point of the CP's axis to the centre, and the section's elliptic
//                support along the line to the centre (exact for a sphere against the elliptic
//                cylinder where the section is circular; the ellipse's support elsewhere); a sphere
//                apart at the start meets the CP at gap / approach speed when that is within the step.
#pragma once
#include "bound/OBB.hpp"
#include "fabric/Fabric.hpp"
#include "shape/RigidBody.hpp"
#include "shape/Section.hpp"
#include <vector>

namespace woven {

struct BodyContact {
  Index cp = -1;               ///< the CP
  int body = -1, part = -1;    ///< index of the body in the stage's list, and of its part
  Vec3 normal = Vec3::UnitZ(); ///< unit, from the CP towards the body
  /// Separation of the CP's surface and the body's along `normal` [m]; < 0 overlap. For a contact
  /// found by the moving test, the distance closed before the first time of contact plus the margin.
  Real gap = 0;
  Vec3 point = Vec3::Zero();   ///< contact point [m]
  Real s = 0.5;                ///< where the point lies along the CP (weight of its 2nd node)
  Real time = 0;               ///< first time of contact within the step [s] (0: touching at the start)
  /// Gap model (geom/GapFunction.hpp): the form used, and what it holds for the step. Sphere: the
  /// section frame at s (u, d, semi-axes a, b). Box: the normal in the body frame (it turns with
  /// the body) and the two end sections' supports along it.
  bool gapModel = false;
  Vec3 secU = Vec3::Zero(), secD = Vec3::Zero();
  Real secA = 0, secB = 0;
  Vec3 localNormal = Vec3::Zero();
  Real support[2] = {0, 0};
  /// What the measure memory holds back [m]: the CP's sections as they stand reach this much further
  /// into the body than the held ones the gap is measured with (CPContact::hHeld's rule); the
  /// flattening passes must take it before the gap can grow.
  Real held = 0;
  /// Sphere form: -1, the contact is at the centre's place along the CP; 0 or 1, at that end node
  /// (the section there, as a circle of its half-thickness: GapFunction.cpp, bodyGap). Triangle
  /// form: 0 or 1, the end node over the face; -1, the edge or corner contact. Part of the key its
  /// memory is found by at the next step.
  std::int8_t end = -1;
};

/// Contact of CP `cp` (box `cpBox`, the bound functor's OBB) with part `part` of `body` within the
/// step dt [s] (dt = 0: static only). True and `out` when they touch or meet within the step.
bool cpBodyContact(const Fabric& f, const OBB& cpBox, Index cp, const RigidBody& body, int part, Real dt, Real margin,
                   SectionRule rule, BodyContact& out);

}  // namespace woven
