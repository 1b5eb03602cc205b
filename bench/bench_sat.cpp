// Narrow phase cost per box pair, single thread, against ODE's dBoxBox / dBoxTouchesBox on the same
// random pairs in the same run (a third yarn-shaped, about 40 % overlapping):
//   bench_sat [pairs = 200000] [repeats = 10]
// Prints ns per pair for: obbOverlap (yes/no), obbContact (exact TD + contact points), ODE
// dBoxTouchesBox (yes/no), ODE dBoxBox (face-preferring depth + up to 8 contacts), and the ratios;
// then the same on yarn crossings (warp and weft boxes crimped by up to 0.3 rad, pressed up to
// 45 um: their section axes are near parallel, so the SAT takes its exact edge axes there).
#include "../tests/cpp/box_util.hpp"
#include "geom/SeparatingAxis.hpp"
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ode/ode.h>
#include <vector>

using namespace woven;

namespace {
struct OdeBox {
  dVector3 p, side;
  dMatrix3 R;
};
template <class F>
double nsPerPair(std::size_t n, int repeats, F f) {
  const auto t0 = std::chrono::steady_clock::now();
  long sink = 0;
  for (int r = 0; r < repeats; ++r)
    for (std::size_t k = 0; k < n; ++k) sink += f(k);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (sink == -1) std::printf(" ");
  return s / (double(n) * repeats) * 1e9;
}

// A warp piece along x and a weft piece along y (half extents 0.1 x 0.3 x 0.03 mm), each crimped by
// up to 0.3 rad about its width axis and the weft turned by up to 0.3 rad, pressed 0-45 um.
void yarnCrossing(std::mt19937& rng, OBB& a, OBB& b) {
  std::uniform_real_distribution<Real> u(-1, 1);
  const Mat3 R0 = woven_test::randomRotation(rng);
  auto about = [](const Vec3& axis, Real angle) { return Eigen::AngleAxis<Real>(angle, axis).toRotationMatrix(); };
  a.extent = b.extent = Vec3(0.1e-3, 0.3e-3, 0.03e-3);
  a.axes = R0 * about(Vec3::UnitY(), 0.3 * u(rng));
  b.axes = R0 * about(Vec3::UnitZ(), M_PI / 2 + 0.3 * u(rng)) * about(Vec3::UnitY(), 0.3 * u(rng));
  a.centre = Vec3::Zero();
  b.centre = R0 * Vec3(0.2e-3 * u(rng), 0.2e-3 * u(rng), 0.06e-3 - 22.5e-6 * (1 + u(rng)));
}

void run(const char* title, std::size_t n, int repeats, unsigned seed, bool yarns) {
  std::mt19937 rng(seed);
  std::vector<OBB> A(n), B(n);
  std::vector<OdeBox> OA(n), OB(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (yarns) yarnCrossing(rng, A[k], B[k]);
    else A[k] = woven_test::randomBox(rng, 1.0), B[k] = woven_test::randomBox(rng, 1.0);
    for (auto [src, dst] : {std::pair{&A[k], &OA[k]}, std::pair{&B[k], &OB[k]}})
      for (int i = 0; i < 3; ++i) {
        dst->p[i] = src->centre[i], dst->side[i] = 2 * src->extent[i], dst->R[i * 4 + 3] = 0;
        for (int j = 0; j < 3; ++j) dst->R[i * 4 + j] = src->axes(i, j);
      }
  }
  long overlapping = 0;
  for (std::size_t k = 0; k < n; ++k) overlapping += obbOverlap(A[k], B[k]);
  const double ours = nsPerPair(n, repeats, [&](std::size_t k) { return long(obbOverlap(A[k], B[k])); });
  const double oursC = nsPerPair(n, repeats, [&](std::size_t k) { return long(obbContact(A[k], B[k]).nPoints); });
  const double ode = nsPerPair(n, repeats, [&](std::size_t k) {
    return long(dBoxTouchesBox(OA[k].p, OA[k].R, OA[k].side, OB[k].p, OB[k].R, OB[k].side));
  });
  const double odeC = nsPerPair(n, repeats, [&](std::size_t k) {
    dVector3 nrm;
    dReal depth;
    int code;
    dContactGeom c[8];
    return long(dBoxBox(OA[k].p, OA[k].R, OA[k].side, OB[k].p, OB[k].R, OB[k].side, nrm, &depth, &code, 8, c,
                        sizeof(dContactGeom)));
  });
  std::printf("%spairs %zu x %d, %.1f %% overlapping\n", title, n, repeats, 100.0 * overlapping / n);
  std::printf("woven obbOverlap (yes/no)          : %7.1f ns/pair\n", ours);
  std::printf("ODE   dBoxTouchesBox (yes/no)      : %7.1f ns/pair   ratio woven/ODE %.2f\n", ode, ours / ode);
  std::printf("woven obbContact (exact TD+points) : %7.1f ns/pair\n", oursC);
  std::printf("ODE   dBoxBox (depth+contacts)     : %7.1f ns/pair   ratio woven/ODE %.2f (goal <= 1)\n", odeC, oursC / odeC);
}
}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 200000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 10;
  dInitODE();
  run("", n, repeats, 99, false);
  run("yarn crossings: ", n, repeats, 98, true);
  dCloseODE();
  return 0;
}
