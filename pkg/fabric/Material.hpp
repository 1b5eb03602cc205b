// Yarn material and section: what a yarn is made of and how thick it is.
#pragma once
#include "core/Types.hpp"
#include <string>

namespace woven {

/// Axial material of a yarn (the spring of a CP, paper Eq. 3).
struct YarnMaterial {
  Real E = 90e9;               ///< Young's modulus of the fibre [Pa]
  Real rho = 1440.0;           ///< fibre density [kg/m^3]
  Real area = 4.63e-8;         ///< load-bearing (fibre) cross-section area of the yarn [m^2]
  Real dampingRatio = 0.0;     ///< xi: c = xi*sqrt(K*m_e) per element [-], damping ratio of the highest chain mode
  Real failureStrain = 0.05;   ///< strain at break [-] (used by the breakage model)
  bool tensionOnly = true;     ///< a yarn does not push: no axial force while shorter than its rest length
  /// Bending stiffness EI of the yarn [N m^2]; 0: none (the paper's chain). A discrete bending energy
  /// at each interior node (dynamics/ChainDynamics.hpp, bendingForces); straight at rest.
  Real bending = 0.0;

  /// Throws ParameterError naming the bad field and its range.
  void validate(const std::string& prefix = "") const;
};

/// Elliptic yarn cross-section at rest: width (in the fabric plane) and thickness (normal to it).
struct YarnSection {
  Real width = 0.65e-3;        ///< [m]
  Real thickness = 0.12e-3;    ///< [m]
  void validate(const std::string& prefix = "") const;
};

}  // namespace woven
