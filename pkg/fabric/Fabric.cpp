#include "fabric/Fabric.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

Index Fabric::addYarn(const Vec3Array& pts, const YarnMaterial& mat, const YarnSection& sec,
                      YarnFamily family) {
  // Everything is checked before anything is appended: a refused yarn used to leave its nodes
  // behind without an inverse mass, and the next step read past the end of invMass.
  mat.validate();
  sec.validate();
  require(pts.size() >= 2, "points", static_cast<double>(pts.size()), "at least 2 nodes per yarn");
  // Index is 32-bit: the fabric's nodes and elements must stay addressable.
  require(static_cast<double>(pts.size()) + nNodes() < 2147483647.0, "points", static_cast<double>(pts.size()),
          "at most 2^31 - 1 nodes in a fabric");
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const Vec3& p = pts[k];
    require(p.allFinite() && p.cwiseAbs().maxCoeff() <= 1e3, "points", p.allFinite() ? p.cwiseAbs().maxCoeff() : NAN,
            "finite coordinates within [-1e3, 1e3] m (point " + std::to_string(k) + ")");
  }
  const Index nE = static_cast<Index>(pts.size()) - 1;
  std::vector<Real> l0(nE), K(nE), me(nE), c(nE);
  for (Index j = 0; j < nE; ++j) {
    l0[j] = (pts[j + 1] - pts[j]).norm();
    require(l0[j] >= 1e-9, "points", l0[j], "consecutive nodes at least 1e-9 m apart (element length)");
    K[j] = mat.E * mat.area / l0[j];
    me[j] = mat.rho * mat.area * l0[j];
    // c = xi*sqrt(K*m_e): xi is then the damping ratio of the chain's highest mode
    // (omega_max = 2*sqrt(K/m_node), m_node = m_e for a uniform chain).
    c[j] = mat.dampingRatio * std::sqrt(K[j] * me[j]);
    // Derived quantities must be usable: finite stiffness, mass and damping and a finite, positive
    // critical step (a range check on each input alone does not guarantee it).
    const Real xi = c[j] / std::sqrt(K[j] * me[j]);
    const Real dtc = std::sqrt(me[j] / K[j]) * (std::sqrt(1 + xi * xi) - xi);
    require(std::isfinite(K[j]) && K[j] > 0 && std::isfinite(me[j]) && me[j] > 0 && std::isfinite(1 / me[j]) &&
                std::isfinite(c[j]) && std::isfinite(dtc) && dtc > 0,
            "material", K[j], "E, rho, area and the element length giving a finite stiffness, mass, damping and "
            "critical time step");
  }

  Yarn y;
  y.firstNode = nNodes();
  y.nNodes = static_cast<Index>(pts.size());
  y.firstElem = nElems();
  y.nElems = nE;
  y.family = family;
  y.section = sec;
  y.material = static_cast<Index>(materials.size());
  materials.push_back(mat);
  const Index yi = nYarns();
  // The section starts circular with the area of the nominal ellipse (pi*w*t/4): flattened at
  // constant area to the nominal thickness it has exactly the nominal width.
  const Real r0 = 0.5 * std::sqrt(sec.width * sec.thickness);

  for (const Vec3& p : pts) {
    pos.push_back(p);
    vel.push_back(Vec3::Zero());
    force.push_back(Vec3::Zero());
    mass.push_back(0.0);
    nodeYarn.push_back(yi);
    restTurn.push_back(0.0);
    secRadius.push_back(r0);
    secFlat.push_back(0.0);
    secDir.push_back(Vec3::UnitZ());  // any normal to the yarn: made so by updateSectionFrames
  }
  for (Index j = 0; j < nE; ++j) {
    const Index a = y.firstNode + j;
    elem0.push_back(a);
    restLength.push_back(l0[j]);
    stiffness.push_back(K[j]);
    damping.push_back(c[j]);
    strain.push_back(0.0);
    tension.push_back(0.0);
    alive.push_back(1);
    elemYarn.push_back(yi);
    mass[a] += 0.5 * me[j];
    mass[a + 1] += 0.5 * me[j];
  }
  for (Index k = 1; k < nE; ++k) {  // the turn between the chords at each interior node
    const Vec3 u = (pts[k] - pts[k - 1]).normalized(), w = (pts[k + 1] - pts[k]).normalized();
    restTurn[y.firstNode + k] = std::atan2(u.cross(w).norm(), u.dot(w));
  }
  invMass.resize(mass.size());
  for (Index i = y.firstNode; i < nNodes(); ++i) invMass[i] = 1.0 / mass[i];
  yarns.push_back(y);
  return yi;
}

Real Fabric::elementMass(Index e) const {
  const YarnMaterial& m = materials[yarns[elemYarn[e]].material];
  return m.rho * m.area * restLength[e];
}

Real Fabric::totalMass() const {
  Real s = 0;
  for (Real m : mass) s += m;
  return s;
}

void Fabric::checkNode(Index i, const char* p) const {
  require(i >= 0 && i < nNodes(), p, i, "[0, " + fmt(nNodes() - 1) + "]");
}
void Fabric::checkElem(Index e, const char* p) const {
  require(e >= 0 && e < nElems(), p, e, "[0, " + fmt(nElems() - 1) + "]");
}

}  // namespace woven
