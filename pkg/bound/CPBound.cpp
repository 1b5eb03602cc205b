#include "bound/CPBound.hpp"
#include "core/Parallel.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

// Each node on its own (threads: Parallel.hpp).
void updateSectionFrames(Fabric& f, Vec3Array& tangent) {
  tangent.resize(f.pos.size());
  parallelFor(f.nNodes(), kParallelGrain, threads(), [&](Index k) { turnSectionFrame(f, k, tangent); });
}

OBB cpBound(const Fabric& f, const Vec3Array& tangent, Index e, SectionRule rule, Real margin) {
  const Index i = f.elem0[e], j = i + 1;
  const Vec3 &x0 = f.pos[i], &x1 = f.pos[j];
  OBB b;
  b.centre = 0.5 * (x0 + x1);
  const Vec3 A0 = (x1 - x0).normalized();
  const Vec3 &d0 = f.secDir[i], &d1 = f.secDir[j];
  Vec3 dm = d0 + (d0.dot(d1) < 0 ? Vec3(-d1) : d1);
  dm -= dm.dot(A0) * A0;
  const Real len = dm.norm();
  const Vec3 A2 = len > 1e-9 ? Vec3(dm / len) : A0.unitOrthogonal();
  b.axes.col(0) = A0;
  b.axes.col(1) = A2.cross(A0);
  b.axes.col(2) = A2;
  // Each node's section (semi-axes and major axis) once, for the three box axes.
  const Index node[2] = {i, j};
  const SemiAxes s[2] = {semiAxes(f.secRadius[i], f.secFlat[i], rule), semiAxes(f.secRadius[j], f.secFlat[j], rule)};
  const Vec3 u[2] = {tangent[i].cross(f.secDir[i]), tangent[j].cross(f.secDir[j])};
  for (int ax = 0; ax < 3; ++ax) {
    const Vec3 w = b.axes.col(ax);
    Real ext = 0;
    for (int q = 0; q < 2; ++q) {
      const Index k = node[q];
      ext = std::max(ext, std::abs((f.pos[k] - b.centre).dot(w)) + ellipseSupport(u[q], f.secDir[k], s[q].a, s[q].b, w));
    }
    b.extent[ax] = ext + margin;
  }
  return b;
}

void refitBounds(const Fabric& f, const Vec3Array& tangent, SectionRule rule, Real margin, std::vector<OBB>& boxes) {
  boxes.resize(f.elem0.size());
  parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) { boxes[e] = cpBound(f, tangent, e, rule, margin); });
}

}  // namespace woven
