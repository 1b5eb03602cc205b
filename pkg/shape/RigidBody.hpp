// Rigid bodies the fabric collides with: proxies of YADE bodies (a projectile, clamps). YADE owns
// and integrates them; each step the engine adapter copies in their pose and velocities and copies
// out the velocity changes of the impulses (py/woven/coupling.py), so the exchange costs in
// proportion to the number of bodies, never the number of nodes.
//
// A body is a set of parts (one for a Box or a Sphere, one per member for a YADE clump) fixed in the
// body frame. Mass and principal inertia as YADE's State: `inertia` is the diagonal of the inertia
// tensor in the body's principal frame, `ori` turns that frame into the global one.
#pragma once
#include "bound/OBB.hpp"
#include "shape/Triangle.hpp"
#include "core/Types.hpp"
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

namespace woven {

using Quat = Eigen::Quaternion<Real>;

struct RigidPart {
  // Cylinder: YADE has no such body; a standard projectile (RCC, FSP) is a YADE body whose mass and
  // inertia are those of this exact solid, shown in YADE by a stand-in shape (shape/Cylinder.hpp).
  // Triangle: one face of a mesh (a YADE Facet, a clump of them, an STL solid: shape/Triangle.hpp).
  enum class Type : std::uint8_t { Box = 0, Sphere = 1, Cylinder = 2, Triangle = 3 };
  Type type = Type::Box;
  Vec3 halfSize = Vec3::Zero();  ///< box half-extents in the part frame [m] (YADE Box.extents)
  Real radius = 0;               ///< sphere or cylinder radius [m]
  Real halfLength = 0;           ///< cylinder: half its length along the part's z axis [m]
  Real chiselAngle = 0;          ///< cylinder: angle of the chisel nose's two flats to the axis [rad]; 0: none
  Real landHalfWidth = 0;        ///< cylinder with a chisel: half-width of the flat tip the flats leave [m]
  /// Triangle: its corners in the part frame [m], counter-clockwise seen from outside: the face
  /// normal (v1 - v0) x (v2 - v0) points out of the solid the mesh closes.
  Vec3 vert[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  /// Triangle: a lone facet, outside on both faces (a YADE Facet, an open sheet); false: a face of a
  /// closed mesh, whose inside is behind it (an axis found behind the face is an overlap to push out).
  bool twoSided = false;
  Vec3 offset = Vec3::Zero();    ///< part centre in the body frame [m]
  Quat ori = Quat::Identity();   ///< part frame in the body frame
};

struct RigidBody {
  long id = -1;                  ///< the YADE body id (for the adapter; woven does not use it)
  std::vector<RigidPart> parts;
  Real mass = 0;                 ///< [kg]; 0 (or inf): kinematic, impulses do not change its motion
  Vec3 inertia = Vec3::Zero();   ///< principal moments [kg m^2] (0 on an axis: no rotation about it)
  Vec3 pos = Vec3::Zero();       ///< centre of mass [m]
  Quat ori = Quat::Identity();
  Vec3 vel = Vec3::Zero();       ///< [m/s]
  Vec3 angVel = Vec3::Zero();    ///< [rad/s], global frame
  /// Coulomb coefficient between this body and the yarns, in [0, 2]; negative: the law's
  /// body_friction (ContactParams::bodyFriction). A clamp's jaws hold the yarns by their own
  /// friction, whatever the projectile's.
  Real friction = -1;
  /// The velocity the host's integrator added over its last step [m/s]: YADE's NewtonIntegrator kicks
  /// the body by O.dt (gravity + forces) / m between two woven steps, so this is the velocity
  /// setHostState reads less the one woven left the body with. The energy books count the body's
  /// kinetic energy at its synchronised velocity vel - hostKick/2, as they count the nodes' at
  /// v_{n+1/2} - dt/2 a_n (law/ImpulseLaw): at the half-step velocity, a body resting on the fabric under
  /// gravity did (M/2)(g dt)^2 of work a step that it never did. Not state: taken every
  /// step (0 when the host leaves the velocity alone, as without gravity; a velocity set by hand in
  /// the host between two steps counts as that step's kick).
  Vec3 hostKick = Vec3::Zero();

  bool dynamic() const { return mass > 0 && std::isfinite(mass); }
  Real invMass() const { return dynamic() ? 1 / mass : 0.0; }
  /// Inverse inertia tensor in the global frame [1/(kg m^2)].
  Mat3 invInertiaWorld() const {
    if (!dynamic()) return Mat3::Zero();
    Vec3 d;
    for (int k = 0; k < 3; ++k) d[k] = inertia[k] > 0 && std::isfinite(inertia[k]) ? 1 / inertia[k] : 0.0;
    const Mat3 R = ori.toRotationMatrix();
    return R * d.asDiagonal() * R.transpose();
  }
  /// Farthest point of part k from its own centre [m] (a bound for its travel as the body turns).
  Real partReach(std::size_t k) const {
    const RigidPart& p = parts[k];
    if (p.type == RigidPart::Type::Triangle)
      return std::max({p.vert[0].norm(), p.vert[1].norm(), p.vert[2].norm()});
    return std::max(p.halfSize.norm(), std::hypot(p.radius, p.halfLength));
  }
  /// Corner j of triangle part k in the global frame [m].
  Vec3 partVertex(std::size_t k, int j) const { return pos + ori * (parts[k].offset + parts[k].ori * parts[k].vert[j]); }
  /// Velocity of the body's material point at p [m/s].
  Vec3 velocityAt(const Vec3& p) const { return vel + angVel.cross(p - pos); }
  /// Part k in the global frame: its centre and axes.
  Vec3 partCentre(std::size_t k) const { return pos + ori * parts[k].offset; }
  Mat3 partAxes(std::size_t k) const { return (ori * parts[k].ori).toRotationMatrix(); }
  /// The OBB of a box part, the cube around a sphere part, the box around a cylinder, the flat box
  /// of a triangle (for the broad phase).
  OBB partBox(std::size_t k) const {
    if (parts[k].type == RigidPart::Type::Triangle)
      return triangleBox(partVertex(k, 0), partVertex(k, 1), partVertex(k, 2));
    OBB b;
    b.centre = partCentre(k);
    b.axes = partAxes(k);
    const RigidPart& p = parts[k];
    b.extent = p.type == RigidPart::Type::Box       ? p.halfSize
               : p.type == RigidPart::Type::Sphere ? Vec3::Constant(p.radius)
                                                   : Vec3(p.radius, p.radius, p.halfLength);
    return b;
  }
  /// Kinetic energy 1/2 m v^2 + 1/2 w . I w [J] (0 for a kinematic body).
  Real kineticEnergy() const {
    if (!dynamic()) return 0;
    const Vec3 wl = ori.conjugate() * angVel;
    return 0.5 * mass * vel.squaredNorm() + 0.5 * wl.dot(inertia.cwiseProduct(wl));
  }
  /// Angular momentum I w in the global frame [kg m^2/s]: what YADE integrates an aspherical body
  /// (a clump) through, so the host gets it with the angular velocity.
  Vec3 angularMomentum() const {
    const Vec3 wl = ori.conjugate() * angVel;
    return ori * Vec3(inertia.cwiseProduct(wl));
  }
  /// Takes the host's state (YADE's State). With `rewind` the host's integrator ran before this
  /// step in the same iteration and already moved the body from x_n to x_n + dt v: the pose is taken
  /// back to x_n (the engine adapters, py/woven_module.cpp and engine/HostBridge).
  void setHostState(Vec3 p, Quat q, const Vec3& v, const Vec3& w, Real dt, bool rewind) {
    if (rewind) {
      p -= dt * v;
      const Real angle = w.norm() * dt;
      if (angle > 0) q = (Quat(Eigen::AngleAxis<Real>(-angle, w.normalized())) * q).normalized();
    }
    hostKick = v - vel;
    pos = p, ori = q, vel = v, angVel = w;
  }
  /// Throws ParameterError naming the field ("mass", "inertia", "parts", ...) and its range.
  void validate() const;
};

}  // namespace woven
