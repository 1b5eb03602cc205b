// Narrow phase cost per box pair, single thread, against ODE's dBoxBox / dBoxTouchesBox on the same
// random pairs in the same run (a third yarn-shaped, about 40 % overlapping):
//   bench_sat [pairs = 200000] [repeats = 10]
// Prints ns per pair for: obbOverlap (yes/no), obbContact (exact TD + contact points), ODE
// dBoxTouchesBox (yes/no), ODE dBoxBox (face-preferring depth + up to 8 contacts), and the ratios.
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
}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 200000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 10;
  dInitODE();
  std::mt19937 rng(99);
  std::vector<OBB> A(n), B(n);
  std::vector<OdeBox> OA(n), OB(n);
  for (std::size_t k = 0; k < n; ++k) {
    A[k] = woven_test::randomBox(rng, 1.0), B[k] = woven_test::randomBox(rng, 1.0);
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
  dCloseODE();
  std::printf("pairs %zu x %d, %.1f %% overlapping\n", n, repeats, 100.0 * overlapping / n);
  std::printf("woven obbOverlap (yes/no)          : %7.1f ns/pair\n", ours);
  std::printf("ODE   dBoxTouchesBox (yes/no)      : %7.1f ns/pair   ratio woven/ODE %.2f\n", ode, ours / ode);
  std::printf("woven obbContact (exact TD+points) : %7.1f ns/pair\n", oursC);
  std::printf("ODE   dBoxBox (depth+contacts)     : %7.1f ns/pair   ratio woven/ODE %.2f (goal <= 1)\n", odeC, oursC / odeC);
  return 0;
}
