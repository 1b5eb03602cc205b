// The narrow interface a host program (the native YADE plugin, pkg/yade/) uses to drive a
// FabricEngine without seeing woven's classes: the engine is an opaque type here and the rigid
// bodies travel as plain doubles. The plugin is compiled with YADE's definitions (EIGEN_DONT_ALIGN,
// EIGEN_DONT_VECTORIZE: other Eigen layouts and other rounding), woven's core with its own; through
// this header neither sees the other's Eigen types, so the core's code, and its bits, are those of
// the default build (docs/yade_native.md). Nothing here includes Eigen.
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace woven {

class FabricEngine;

/// A coupled rigid body as the host holds it: SI, quaternion as x, y, z, w.
struct HostBody {
  long id = -1;          ///< the host's body id (YADE's Body::id)
  bool dynamic = false;  ///< impulses change its motion (written back by hostStep)
  double pos[3] = {0, 0, 0}, ori[4] = {0, 0, 0, 1}, vel[3] = {0, 0, 0}, angVel[3] = {0, 0, 0};
  double angMom[3] = {0, 0, 0};  ///< out: ori * (I (ori^-1 angVel)), the angular momentum YADE integrates clumps by
};

/// The bodies coupled to e's collision stage (ids and whether they are dynamic), in order.
void hostBodies(const FabricEngine& e, std::vector<HostBody>& out);
/// One step of the YADE adapter: the bodies' state in (pos, ori, vel, angVel of x_n..., rewound over
/// dt first when `rewind`: a NewtonIntegrator already moved them), FabricEngine::step(dt), and the
/// dynamic bodies' new pose, velocities and angular momentum out into `bodies`. The same operations
/// as the PyRunner adapter's _yade_step (py/woven_module.cpp), so the same bits.
void hostStep(FabricEngine& e, double dt, std::vector<HostBody>& bodies, bool rewind);
long hostNodes(const FabricEngine& e);

/// What a viewer needs to draw the yarns as tubes of their elliptic sections, as plain numbers.
struct HostTubes {
  /// Per node: x y z [m], semi-axes a (major) b (minor) [m] with the collision stage's section rule
  /// (constant area when collisions are off), minor-axis direction dx dy dz: 8 doubles per node.
  std::vector<double> nodes;
  /// Per live element (CP): its first node (the second is the next one) and its strain (l - l0)/l0.
  std::vector<int> elements;
  std::vector<double> strain;
};
void hostTubes(const FabricEngine& e, HostTubes& out);

/// Identity of this core library's build: the native build's CMake gives the core and the Python
/// module one random id (WOVEN_BUILD_ID); the plugin compares it with woven._woven._build_id(), a
/// literal compiled into the module itself, so a module of another build is never driven by the
/// plugin (py/woven/_native.py). "static" for a core built without an id.
const char* coreBuildId();

/// The collision stage's settings as plain data: ContactParams and the broad phase, enums by the names
/// FabricEngine.enable_collisions takes. The plugin shows them as its own YADE objects (WovenCPShape,
/// WovenCPBound, WovenCollider, WovenGeomFunctor, WovenPhys, WovenImpulseLaw; pkg/yade/WovenStage.hpp).
struct HostStageParams {
  bool collisions = false;  ///< out: the fabric has a collision stage (false: the rest are the defaults)
  // the CP's elliptic sections (shape/Section, the flattening of law/Flatten)
  std::string sectionRule, flattening;
  double mcd = 0;
  int flattenPasses = 0;
  // the OBB bound functor (bound/CPBound)
  double margin = 0;
  // the collider (broad phase)
  std::string broadPhase;
  double skin = 0;
  int selfExclude = 0;
  bool yarnContacts = true;
  int threads = 0;
  double gridCell = 0;  ///< out: cell size of the grid collider's last broad phase [m] (0: none yet)
  // the geometry functor (narrow phase)
  std::string model;
  double cacheDistance = 0;
  // the contact physics of the force responses
  double penaltyStiffness = 0, penaltyDamping = 0, sectionStiffness = 0;
  // the law (impulses, position projection / correction)
  std::string response, sweepOrder;
  double restitution = 0, friction = 0, bodyFriction = 0, tolerance = 0, positionCorrection = 0, correctionSlop = 0;
  double projectionSlop = 0, projectionMaxMove = 0, projectionCheck = 0;
  int maxIterations = 0, projectionSweeps = 0;
};
/// The settings of e's collision stage (collisions off: ContactParams' defaults, collisions = false).
void hostStageParams(const FabricEngine& e, HostStageParams& out);
/// The defaults (FabricEngine.enable_collisions() with no arguments).
void hostStageDefaults(HostStageParams& out);
/// Applies p to e's collision stage as FabricEngine.enable_collisions does (pairs and carried contacts
/// are measured again). Validates first: throws ParameterError (the enable_collisions name of the
/// parameter) and changes nothing on bad input, or when collisions are off.
void hostSetStageParams(FabricEngine& e, const HostStageParams& p);

// pkg/engine/Snapshot.hpp, declared here for hosts that do not include woven's classes.
std::string engineSnapshot(FabricEngine& e);
std::shared_ptr<FabricEngine> restoreSnapshot(const std::string& bytes);

}  // namespace woven
