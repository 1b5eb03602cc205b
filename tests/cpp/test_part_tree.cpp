// The bound tree of a many-part body (collider/BodyCollider's PartTree): every (CP, triangle) pair
// whose triangle comes within the skin of the CP's box is a candidate, each once, in the flat lists'
// order, for a mesh of 600 random triangles turned at random and CPs scattered through it.
#include "collider/BodyCollider.hpp"
#include "chain_util.hpp"
#include <gtest/gtest.h>
#include <random>
#include <set>

using namespace woven;
using namespace woven_test;

TEST(PartTree, ListsEveryTriangleTheFlatTestLists) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<Real> u(-1, 1);
  RigidBody b;
  b.id = 7, b.mass = 1e-3, b.inertia = Vec3::Constant(1e-9);
  b.ori = Quat(Eigen::AngleAxis<Real>(0.7, Vec3(1, 2, 3).normalized()));
  b.pos = Vec3(1e-3, -2e-3, 0.5e-3);
  for (int k = 0; k < 600; ++k) {
    RigidPart p;
    p.type = RigidPart::Type::Triangle;
    const Vec3 c = 4e-3 * Vec3(u(rng), u(rng), u(rng));
    for (Vec3& v : p.vert) v = c + 0.4e-3 * Vec3(u(rng), u(rng), u(rng));
    b.parts.push_back(p);
  }
  YarnSection sec;
  sec.width = 0.65e-3, sec.thickness = 0.11e-3;
  Fabric f;
  for (int y = 0; y < 40; ++y) {
    const Vec3 a = b.pos + 5e-3 * Vec3(u(rng), u(rng), u(rng)), d = Vec3(u(rng), u(rng), u(rng)).normalized();
    f.addYarn({a, a + 0.5e-3 * d, a + 1e-3 * d}, km2Material(), sec);
  }
  std::vector<OBB> grown(f.nElems());
  for (Index e = 0; e < f.nElems(); ++e) {
    const Vec3 p0 = f.pos[f.elem0[e]], p1 = f.pos[f.elem0[e] + 1];
    grown[e].centre = 0.5 * (p0 + p1);
    grown[e].extent = 0.5 * (p1 - p0).cwiseAbs() + Vec3::Constant(0.2e-3);
  }
  const std::vector<Real> grow(f.nElems(), 1e-6);
  BodyCollider col;
  col.skin = 1e-4;
  std::vector<BodyCandidate> out;
  col.collide(f, grown, grow, {b}, 1e-7, out);
  std::set<std::pair<int, Index>> listed;
  for (const BodyCandidate& c : out) listed.emplace(c.part, c.cp);
  EXPECT_EQ(listed.size(), out.size()) << "each pair once";
  // Every triangle that comes within the skin of a CP's box: the distance from a sampling of the
  // triangle (231 points; a sampled minimum is never below the true one) to the box in closed form,
  // at most 0.9 skin (the tree pads the box in the body's frame by the skin, which holds the ball).
  int expected = 0;
  const Real pad = col.skin;
  for (std::size_t k = 0; k < b.parts.size(); ++k) {
    const Vec3 v[3] = {b.partVertex(k, 0), b.partVertex(k, 1), b.partVertex(k, 2)};
    for (Index e = 0; e < f.nElems(); ++e) {
      const Vec3 h = aabbHalf(grown[e]);
      Real d = INFINITY;
      const int N = 20;
      for (int i = 0; i <= N; ++i)
        for (int j = 0; i + j <= N; ++j) {
          const Vec3 y = v[0] + (v[1] - v[0]) * (Real(i) / N) + (v[2] - v[0]) * (Real(j) / N);
          d = std::min(d, ((y - grown[e].centre).cwiseAbs() - h).cwiseMax(Vec3::Zero()).norm());
        }
      if (d > 0.9 * pad) continue;
      ++expected;
      EXPECT_TRUE(listed.count({static_cast<int>(k), e})) << "part " << k << " cp " << e;
    }
  }
  EXPECT_GT(expected, 20);
  // Sorted by part, then CP, as the flat lists are.
  for (std::size_t q = 1; q < out.size(); ++q)
    EXPECT_TRUE(std::make_pair(out[q - 1].part, out[q - 1].cp) < std::make_pair(out[q].part, out[q].cp));
  // Far fewer than all pairs: the tree prunes.
  EXPECT_LT(out.size(), b.parts.size() * f.nElems() / 20);
}
