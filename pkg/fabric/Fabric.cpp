#include "fabric/Fabric.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

Index Fabric::addYarn(const Vec3Array& pts, const YarnMaterial& mat, const YarnSection& sec,
                      YarnFamily family) {
  mat.validate();
  sec.validate();
  require(pts.size() >= 2, "points", static_cast<double>(pts.size()), "at least 2 nodes per yarn");
  Yarn y;
  y.firstNode = nNodes();
  y.nNodes = static_cast<Index>(pts.size());
  y.firstElem = nElems();
  y.nElems = y.nNodes - 1;
  y.family = family;
  y.section = sec;
  y.material = static_cast<Index>(materials.size());
  materials.push_back(mat);
  const Index yi = nYarns();
  // The section starts circular with the area of the nominal ellipse (pi*w*t/4): flattened at
  // constant area to the nominal thickness it has exactly the nominal width.
  const Real r0 = 0.5 * std::sqrt(sec.width * sec.thickness);

  for (const Vec3& p : pts) {
    require(p.allFinite(), "points", p.norm(), "finite coordinates [m]");
    pos.push_back(p);
    vel.push_back(Vec3::Zero());
    force.push_back(Vec3::Zero());
    mass.push_back(0.0);
    nodeYarn.push_back(yi);
    secRadius.push_back(r0);
    secFlat.push_back(0.0);
    secDir.push_back(Vec3::UnitZ());  // any normal to the yarn: made so by updateSectionFrames
  }
  for (Index j = 0; j < y.nElems; ++j) {
    const Index a = y.firstNode + j;
    const Real l0 = (pts[j + 1] - pts[j]).norm();
    require(l0 > 0, "points", l0, "distinct consecutive nodes (element length > 0 m)");
    const Real K = mat.E * mat.area / l0;
    const Real me = mat.rho * mat.area * l0;
    elem0.push_back(a);
    restLength.push_back(l0);
    stiffness.push_back(K);
    // c = xi*sqrt(K*m_e): xi is then the damping ratio of the chain's highest mode
    // (omega_max = 2*sqrt(K/m_node), m_node = m_e for a uniform chain).
    damping.push_back(mat.dampingRatio * std::sqrt(K * me));
    strain.push_back(0.0);
    tension.push_back(0.0);
    alive.push_back(1);
    elemYarn.push_back(yi);
    mass[a] += 0.5 * me;
    mass[a + 1] += 0.5 * me;
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
