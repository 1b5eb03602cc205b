// The state of a fabric: yarns as chains of combined particles (CPs). Structure of arrays so the
// hot loops (springs, integration) stream through contiguous memory.
//
// Node i of yarn y is node yarns[y].firstNode + i; element (CP) j of yarn y joins its nodes j and
// j+1, so elem0[e] + 1 is always the second node (chains are contiguous). A broken element keeps its
// slot with alive = 0 and zero stiffness, so indices never shift.
#pragma once
#include "core/Types.hpp"
#include "fabric/Material.hpp"
#include <string>
#include <vector>

namespace woven {

enum class YarnFamily : std::uint8_t { Warp = 0, Weft = 1, Free = 2 };

struct Yarn {
  Index firstNode = 0, nNodes = 0;
  Index firstElem = 0, nElems = 0;
  Index material = 0;          ///< index into Fabric::materials
  YarnFamily family = YarnFamily::Free;
  YarnSection section;
};

struct Fabric {
  // --- nodes (mass lumped at the CP ends) ---
  Vec3Array pos;               ///< position [m]
  Vec3Array vel;               ///< velocity [m/s] (half-step velocity of the leapfrog, like YADE's)
  Vec3Array force;             ///< total force at the current positions [N]
  std::vector<Real> mass;      ///< lumped mass rho*A*l0/2 from each adjoining element [kg]
  std::vector<Real> invMass;   ///< 1/mass, 0 for kinematic (fixed or velocity-driven) nodes [1/kg]
  std::vector<Index> nodeYarn; ///< yarn of each node
  /// The yarn's turn at each node as built, between its two chords [rad] (0 at a yarn's ends): the
  /// rest shape of the bending energy (YarnMaterial::bending), so a weave is built stress-free.
  std::vector<Real> restTurn;

  // --- cross-sections at the nodes (paper Sec. 5.2.2; shape/Section.hpp) ---
  std::vector<Real> secRadius; ///< natural radius r0 of the circular section at rest [m]
  std::vector<Real> secFlat;   ///< cross-sectional deformation eps in [0, MCD] [-] (0: circular)
  Vec3Array secDir;            ///< unit direction of the flattened (minor, b) axis, normal to the yarn [-]

  // --- elements (CPs): element e joins nodes elem0[e] and elem0[e]+1 ---
  std::vector<Index> elem0;
  std::vector<Real> restLength;  ///< l0 [m]
  std::vector<Real> stiffness;   ///< K = E*A/l0 [N/m]
  std::vector<Real> damping;     ///< c [N*s/m]
  std::vector<Real> strain;      ///< (l - l0)/l0 [-], as of the last ChainDynamics::refreshForces()
  std::vector<Real> tension;     ///< axial force, positive in tension [N], as strain
  std::vector<std::uint8_t> alive;
  std::vector<Index> elemYarn;

  std::vector<Yarn> yarns;
  std::vector<YarnMaterial> materials;

  /// Acceleration every free node has besides force/mass [m/s^2] (gravity): ChainDynamics's body
  /// acceleration (setBodyAcceleration sets both), here for the collision stage's energy books, which
  /// count an impulse at the synchronised velocity v_n = v_{n+1/2} - dt/2 (force/mass + this).
  Vec3 bodyAcceleration = Vec3::Zero();

  Index nNodes() const { return static_cast<Index>(pos.size()); }
  Index nElems() const { return static_cast<Index>(elem0.size()); }
  Index nYarns() const { return static_cast<Index>(yarns.size()); }

  /// Appends a yarn through the given node positions [m] (at least 2, distinct). Masses and
  /// stiffnesses follow from the material (K = E*A/l0, node mass rho*A*l0/2 per element, Eq. 3).
  /// Returns the yarn index.
  Index addYarn(const Vec3Array& points, const YarnMaterial& material, const YarnSection& section,
                YarnFamily family = YarnFamily::Free);

  /// Element mass rho*A*l0 [kg] of element e.
  Real elementMass(Index e) const;
  /// Total mass [kg].
  Real totalMass() const;
  /// Throws ParameterError if a node or element index is out of range.
  void checkNode(Index i, const char* parameter = "node") const;
  void checkElem(Index e, const char* parameter = "element") const;
};

}  // namespace woven
