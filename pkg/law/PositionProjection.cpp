#include "law/PositionProjection.hpp"
#include "fabric/SpringEnergy.hpp"
#include "geom/GapFunction.hpp"
#include <cmath>

namespace woven {

void PositionProjection::project(Fabric& f, std::vector<CPContact>& contacts, std::vector<BodyContact>& bodyContacts,
                                 std::vector<RigidBody>& bodies, const Allowance& allowance, int sweeps, Real slop,
                                 Real maxMove, SectionRule rule, Real dt, ProjectionReport& rep) {
  rep = ProjectionReport{};
  if (sweeps <= 0 || (contacts.empty() && bodyContacts.empty())) return;
  allowance_.assign(contacts.size(), NAN);
  marked_.resize(f.nElems(), 0);
  elems_.clear();
  forceBefore_.clear();
  Real before = 0;
  // Before node k moves for the first time, the spring energy of its (at most two) CPs is counted.
  const auto touch = [&](Index k) {
    const Yarn& y = f.yarns[f.nodeYarn[k]];
    const Index local = k - y.firstNode;
    for (Index e : {y.firstElem + local - 1, y.firstElem + local})
      if (e >= y.firstElem && e < y.firstElem + y.nElems && !marked_[e]) {
        marked_[e] = 1, elems_.push_back(e);
        before += springEnergy(f, e);
        forceBefore_.push_back(springForce(f, e));
      }
  };
  // After the first sweep only the contacts with a node (or a body) moved in the sweep before can
  // have changed: the others are skipped (most of a ply is at rest).
  movedNow_.assign(f.nNodes(), 0);
  travel_.assign(f.nNodes(), 0);
  bool bodyMoved = true;
  // The share of a move that moves no node more than maxMove, nor any node more than
  // kTravel x maxMove in all: moves beyond would carry a node into neighbours no contact was listed
  // for (the stage lists the pairs within that much more than the step's motion).
  const auto share = [&](const Index* node, const Real* w, int n, Real dl) {
    Real scale = 1;
    for (int k = 0; k < n; ++k) {
      const Real step = std::abs(w[k] * f.invMass[node[k]] * dl);
      if (step > 0) scale = std::min(scale, std::min(maxMove, std::max(Real(0), kProjectionTravel * maxMove - travel_[node[k]])) / step);
    }
    return scale * dl;
  };
  const auto movedBefore = [&](Index k) { return movedBefore_[k] != 0; };
  // Moves the n nodes of a contact by dl along its gradient (w_k n, weighted by 1/m_k).
  const auto move = [&](const Index* node, const Real* w, int n, Real dl, const Vec3& normal) {
    for (int k = 0; k < n; ++k)
      if (w[k] != 0 && f.invMass[node[k]] > 0) {
        touch(node[k]);
        const Real step = w[k] * f.invMass[node[k]] * dl;
        f.pos[node[k]] += step * normal;
        travel_[node[k]] += std::abs(step);
        movedNow_[node[k]] = 1;
      }
  };
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    ++rep.sweeps;
    bool moved = false, bodyMovedNow = false;
    const bool all = sweep == 0;
    movedBefore_.swap(movedNow_);
    movedNow_.assign(f.nNodes(), 0);
    rep.overlapLeft = 0;
    for (std::size_t q = 0; q < contacts.size(); ++q) {
      CPContact& c = contacts[q];
      if (!f.alive[c.cpA] || !f.alive[c.cpB]) continue;  // broken in this step
      const Index i = f.elem0[c.cpA], j = f.elem0[c.cpB];
      if (!all && !(movedBefore(i) || movedBefore(i + 1) || movedBefore(j) || movedBefore(j + 1))) continue;
      remeasure(f, c, rule, false);
      if (!(c.gap < -slop)) continue;
      if (std::isnan(allowance_[q])) allowance_[q] = allowance(c);
      const Real C = c.gap + allowance_[q] + slop;
      if (!(C < 0)) continue;
      const Index node[4] = {f.elem0[c.cpA], f.elem0[c.cpA] + 1, f.elem0[c.cpB], f.elem0[c.cpB] + 1};
      const Real w[4] = {-(1 - c.sA), -c.sA, 1 - c.sB, c.sB};
      Real K = 0;
      for (int k = 0; k < 4; ++k) K += w[k] * w[k] * f.invMass[node[k]];
      if (!(K > 0)) continue;  // both CPs kinematic
      const Real dl = share(node, w, 4, -C / K);
      if (dl == 0) continue;
      move(node, w, 4, dl, c.normal);
      ++rep.pushed;
      moved = true;
      rep.overlapLeft = std::max(rep.overlapLeft, -C);
    }
    for (BodyContact& c : bodyContacts) {
      if (!f.alive[c.cp]) continue;
      const Index i = f.elem0[c.cp];
      if (!all && !bodyMoved && !(movedBefore(i) || movedBefore(i + 1))) continue;
      RigidBody& b = bodies[c.body];
      remeasureBody(f, b, c);
      const Real C = c.gap + slop;
      if (!(C < 0)) continue;
      const Index node[2] = {f.elem0[c.cp], f.elem0[c.cp] + 1};
      const Real w[2] = {-(1 - c.s), -c.s};
      const Vec3 arm = c.point - b.pos, rn = arm.cross(c.normal);
      const Mat3 invI = b.invInertiaWorld();
      Real K = b.invMass() + rn.dot(invI * rn);
      for (int k = 0; k < 2; ++k) K += w[k] * w[k] * f.invMass[node[k]];
      if (!(K > 0)) continue;  // kinematic CP and body
      const Real dl = share(node, w, 2, -C / K);
      if (dl == 0) continue;
      move(node, w, 2, dl, c.normal);
      if (b.dynamic()) {
        bodyMovedNow = true;
        b.pos += (b.invMass() * dl) * c.normal;
        const Vec3 turn = invI * rn * dl;  // a small rotation [rad]
        const Real angle = turn.norm();
        if (angle > 0) b.ori = (Quat(Eigen::AngleAxis<Real>(angle, turn / angle)) * b.ori).normalized();
      }
      ++rep.pushed;
      moved = true;
      rep.overlapLeft = std::max(rep.overlapLeft, -C);
    }
    bodyMoved = bodyMovedNow;
    if (!moved) break;
  }
  Real after = 0;
  // The step's kinetic energy takes the forces at the moved positions over the whole drift
  // (velocity Verlet: dKE = (F_n + F_{n+1})/2 . dx): the moves change F_{n+1} by dF, and so the
  // kinetic energy by dF . dx / 2, which is booked with the spring energy they put in.
  Real drift = 0;
  for (std::size_t q = 0; q < elems_.size(); ++q) {
    const Index e = elems_[q], i = f.elem0[e];
    after += springEnergy(f, e), marked_[e] = 0;
    const Vec3 dF = springForce(f, e) - forceBefore_[q];  // on node i; its opposite on node i + 1
    const Vec3 v0 = f.invMass[i] > 0 ? f.vel[i] : Vec3::Zero(), v1 = f.invMass[i + 1] > 0 ? f.vel[i + 1] : Vec3::Zero();
    drift += 0.5 * dt * dF.dot(v0 - v1);
  }
  rep.energy = after - before + drift;
}

}  // namespace woven
