#include "law/PositionProjection.hpp"
#include "fabric/SpringEnergy.hpp"
#include "geom/GapFunction.hpp"
#include "core/Parallel.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

namespace {
// Contacts a sweep pushed and the largest overlap one of them took out [m].
struct Pushes {
  long count = 0;
  Real largest = 0;
  void add(Real left) {
    if (left > 0) ++count, largest = std::max(largest, left);
  }
  Pushes& operator+=(const Pushes& o) { return count += o.count, largest = std::max(largest, o.largest), *this; }
};
}  // namespace

void PositionProjection::project(Fabric& f, std::vector<CPContact>& contacts, std::vector<BodyContact>& bodyContacts,
                                 std::vector<RigidBody>& bodies, const Allowance& allowance, int sweeps, Real slop,
                                 Real maxMove, SectionRule rule, Real dt, ProjectionReport& rep, SweepOrder order,
                                 Real checkDepth, const Real* travelled) {
  rep = ProjectionReport{};
  const bool check = checkDepth >= 0;
  // A check's moves count against the travel of the projection after the same step's drift.
  const bool carry = !check && checked_ && travel_.size() == static_cast<std::size_t>(f.nNodes());
  checked_ = check;
  if (!carry) travel_.assign(f.nNodes(), 0);
  if (sweeps <= 0 || (contacts.empty() && bodyContacts.empty())) return;
  const Index nc = static_cast<Index>(contacts.size());
  // The check comes after the flattening passes: it leaves them nothing.
  allowance_.assign(contacts.size(), check ? Real(0) : Real(NAN));
  outcome_.resize(contacts.size());
  // After the first sweep only the contacts with a node (or a body) moved in the sweep before can
  // have changed: the others are skipped (most of a ply is at rest). The check's first sweep takes
  // only the contacts deeper than checkDepth.
  movedNow_.assign(f.nNodes(), 0);
  origin_.resize(f.pos.size());
  nodeSlotsFor_ = -1;
  // The contacts by colour: those of a colour share no node (law/RowColouring), and a contact reads
  // and moves only its own four nodes, so a colour's contacts are projected at once on the threads
  // with the same bits as one after another. The body contacts (all share the body) follow, in order.
  // SweepOrder::Sequential: every contact in the serial tail, in order. SweepOrder::Blocked: the
  // groups of each phase of law/RowBlocks at once (they share no node), each in order, then the
  // seam in order.
  const bool blocked = order == SweepOrder::Blocked;
  Real wUnused[kMaxStencil];
  const auto nodesOf = [&](Index q, Index* node) {
    if (order == SweepOrder::Sequential) return -1;
    return contactStencil(f, contacts[q], node, wUnused);
  };
  if (blocked) blocking_.build(nc, f.pos, nodesOf);
  else colouring_.build(nc, f.nNodes(), nodesOf);
  const std::vector<Index>& layout = blocked ? blocking_.order() : colouring_.order();
  const Index tail = blocked ? blocking_.begin(RowBlocks::kSeam) : colouring_.begin(RowColouring::kColours);
  // What a sweep reads first, in colour order: most contacts are skipped on it alone, without
  // reading the contact (in colour order the contacts are scattered in memory).
  slots_.resize(contacts.size());
  parallelFor(nc, kParallelGrain, threads(), [&](Index k) {
    const Index q = layout[k];
    const CPContact& c = contacts[q];
    Slot& slot = slots_[k];
    Real w[kMaxStencil];
    slot.q = q, slot.cpA = c.cpA, slot.cpB = c.cpB, slot.n = contactStencil(f, c, slot.node, w);
  });
  bool bodyMoved = !check;
  // What a node may travel in all (this call and, after a check, the check before it).
  const Real travelCap = (check ? kCheckTravel : kProjectionTravel) * maxMove;
  // The share of a move that moves no node more than maxMove, nor any node more than
  // kTravel x maxMove in all: moves beyond would carry a node into neighbours no contact was listed
  // for (the stage lists the pairs within that much more than the step's motion).
  const auto share = [&](const Index* node, const Real* w, int n, Real dl) {
    Real scale = 1;
    for (int k = 0; k < n; ++k) {
      const Real step = std::abs(w[k] * f.invMass[node[k]] * dl);
      if (step > 0) scale = std::min(scale, std::min(maxMove, std::max(Real(0), travelCap - travel_[node[k]])) / step);
    }
    return scale * dl;
  };
  const auto movedBefore = [&](Index k) { return movedBefore_[k] != 0; };
  // Moves the n nodes of a contact by dl along its gradient (w_k n, weighted by 1/m_k); a node's
  // position before its first move is kept for the books (travel_ is 0 until then).
  const auto move = [&](const Index* node, const Real* w, int n, Real dl, const Vec3& normal) {
    for (int k = 0; k < n; ++k)
      if (w[k] != 0 && f.invMass[node[k]] > 0) {
        const Real step = w[k] * f.invMass[node[k]] * dl;
        if (!movedAny_[node[k]]) movedAny_[node[k]] = 1, origin_[node[k]] = f.pos[node[k]];
        f.pos[node[k]] += step * normal;
        travel_[node[k]] += std::abs(step);
        movedNow_[node[k]] = 1;
      }
  };
  // The nodes a sweep moved (the sequential order's work list; the books' CPs): from the flags.
  const auto collectMoved = [&](std::vector<Index>& out) {
    out.clear();
    for (Index i = 0; i < f.nNodes(); ++i)
      if (movedNow_[i]) out.push_back(i);
  };
  movedAny_.assign(f.nNodes(), 0);
  // One contact's move; returns the overlap beyond allowance + slop it took out (0: no move) [m].
  const auto projectOne = [&](const Slot& slot, bool first) -> Real {
    const Index q = slot.q;
    if (first ? check && !(contacts[q].gap < -checkDepth)
              : std::none_of(slot.node, slot.node + slot.n, movedBefore))
      return 0;
    if (first && travelled) {  // the gap cannot have closed to -slop since it was measured
      Real far = 0;
      for (int k = 0; k < slot.n; ++k) far = std::max(far, travelled[slot.node[k]]);
      if (contacts[q].gap - 2 * far > -slop) return 0;
    }
    if (!f.alive[slot.cpA] || !f.alive[slot.cpB]) return 0;  // broken in this step
    CPContact& c = contacts[q];
    remeasure(f, c, rule, false);
    if (!(c.gap < -slop)) return 0;
    if (std::isnan(allowance_[q])) allowance_[q] = allowance(c);
    const Real C = c.gap + allowance_[q] + slop;
    if (!(C < 0)) return 0;
    // The gradient at the remeasured points (a CP pair's may have slid; a crossing's are held).
    Index node[kMaxStencil];
    Real w[kMaxStencil];
    const int n = contactStencil(f, c, node, w);
    Real K = 0;
    for (int k = 0; k < n; ++k) K += w[k] * w[k] * f.invMass[node[k]];
    if (!(K > 0)) return 0;  // both CPs kinematic
    const Real dl = share(node, w, n, -(C - kRebound * slop) / K);
    if (dl == 0) return 0;
    move(node, w, n, dl, c.normal);
    return -C;
  };
  const int nThreads = threads();
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    ++rep.sweeps;
    bool moved = false, bodyMovedNow = false;
    const bool first = sweep == 0;
    movedBefore_.swap(movedNow_);
    movedNow_.assign(f.nNodes(), 0);
    rep.overlapLeft = 0;
    // The first sweep measures every contact (a check's, only its seeds): its colours on the
    // threads. The later ones skip most contacts on their slot alone: on one thread, in the same
    // order (the same bits; a barrier per colour would cost more than the work where the cores are
    // busy). The blocks cost three barriers a sweep: every sweep but a check's on the threads.
    // The contacts pushed and the largest overlap they took out: per block by its thread, over the
    // colours' outcomes after them, in the tail as it goes (a count and a maximum: exact in any order).
    Pushes pushes;
    if (blocked) {
      Pushes group[RowBlocks::kSeam];
      for (int phase = 0; phase < RowBlocks::kPhases; ++phase) {
        const int g0 = RowBlocks::phaseBegin(phase);
        parallelFor(RowBlocks::phaseBegin(phase + 1) - g0, 1, check ? 1 : nThreads, [&](Index q) {
          for (Index k = blocking_.begin(g0 + q); k < blocking_.begin(g0 + q + 1); ++k)
            group[g0 + q].add(outcome_[k] = projectOne(slots_[k], first));
        });
      }
      for (const Pushes& g : group) pushes += g;
    } else {
      for (int col = 0; col < colouring_.colours(); ++col) {
        const Index b = colouring_.begin(col);
        parallelFor(colouring_.begin(col + 1) - b, kContactGrain, first && !check ? nThreads : 1,
                    [&](Index k) { outcome_[b + k] = projectOne(slots_[b + k], first); });
      }
      for (Index k = 0; k < tail; ++k) pushes.add(outcome_[k]);
    }
    // The tail (a contact that found no colour free, or the blocks' seam) in order. After the first
    // sweep the sequential order (every contact in the tail) takes only the contacts with a node the
    // sweep before moved, from the nodes' lists of slots: the contacts projectOne would not skip,
    // in the same order (the same bits), without reading the rest.
    if (!first && tail == 0 && order == SweepOrder::Sequential) {
      if (nodeSlotsFor_ != nc) {  // the nodes' slots (CSR), once a second sweep is needed
        nodeSlotsFor_ = nc;
        nodeStart_.assign(f.pos.size() + 1, 0);
        for (Index k = 0; k < nc; ++k)
          for (int q = 0; q < slots_[k].n; ++q) ++nodeStart_[slots_[k].node[q] + 1];
        for (std::size_t i = 1; i < nodeStart_.size(); ++i) nodeStart_[i] += nodeStart_[i - 1];
        nodeSlots_.resize(static_cast<std::size_t>(nodeStart_.back()));
        std::vector<Index> fill(nodeStart_.begin(), nodeStart_.end() - 1);
        for (Index k = 0; k < nc; ++k)
          for (int q = 0; q < slots_[k].n; ++q) nodeSlots_[fill[slots_[k].node[q]]++] = k;
      }
      work_.clear();
      for (Index i : movedBeforeList_)
        for (Index j = nodeStart_[i]; j < nodeStart_[i + 1]; ++j) work_.push_back(nodeSlots_[j]);
      std::sort(work_.begin(), work_.end());
      work_.erase(std::unique(work_.begin(), work_.end()), work_.end());
      for (Index k : work_) pushes.add(outcome_[k] = projectOne(slots_[k], false));
    } else {
      for (Index k = tail; k < nc; ++k) pushes.add(outcome_[k] = projectOne(slots_[k], first));
    }
    if (pushes.count > 0) rep.pushed += pushes.count, moved = true, rep.overlapLeft = pushes.largest;
    for (BodyContact& c : bodyContacts) {
      if (!f.alive[c.cp]) continue;
      const Index i = f.elem0[c.cp];
      if (first ? check && !(c.gap < -checkDepth) : !bodyMoved && !(movedBefore(i) || movedBefore(i + 1))) continue;
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
      const Real dl = share(node, w, 2, -(C - kRebound * slop) / K);
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
    collectMoved(movedBeforeList_);
  }
  // A check moves x_n after its forces made the kick: the drift then misses -dF . dx / 2 (the
  // projection after the drift: +dF . dx / 2). dx is taken with the velocities before the rows.
  rep.energy = bookedEnergy(f, check ? -dt : dt);
}

// The energy the moves put in [J], over the CPs with a moved node, in CP order: their spring energy
// after minus before, and the step's kinetic energy that their changed forces make: velocity Verlet
// takes the forces at the moved positions over the whole drift (dKE = (F_n + F_{n+1})/2 . dx), so
// the moves change F_{n+1} by dF, and the kinetic energy by dF . dx / 2, dx = dt v (dt < 0: the
// moves of a check, before the drift, change F_n instead).
Real PositionProjection::bookedEnergy(Fabric& f, Real dt) {
  elems_.clear();
  for (Index k = 0; k < f.nNodes(); ++k) {
    if (!movedAny_[k]) continue;
    const Yarn& y = f.yarns[f.nodeYarn[k]];
    const Index local = k - y.firstNode;
    for (Index e : {y.firstElem + local - 1, y.firstElem + local})
      if (e >= y.firstElem && e < y.firstElem + y.nElems && (elems_.empty() || elems_.back() != e)) elems_.push_back(e);
  }
  if (elems_.empty()) return 0;
  // The CPs before the moves: the moved nodes put back where they were for the measure, then returned.
  const auto swapMoved = [&] {
    for (Index e : elems_)
      for (Index k : {f.elem0[e], f.elem0[e] + 1})
        if (movedAny_[k] == 1) std::swap(f.pos[k], origin_[k]), movedAny_[k] = 2;
    for (Index e : elems_)
      for (Index k : {f.elem0[e], f.elem0[e] + 1})
        if (movedAny_[k] == 2) movedAny_[k] = 1;
  };
  swapMoved();
  Real before = 0;
  forceBefore_.resize(elems_.size());
  for (std::size_t q = 0; q < elems_.size(); ++q) before += springEnergy(f, elems_[q]), forceBefore_[q] = springForce(f, elems_[q]);
  swapMoved();
  Real after = 0, drift = 0;
  for (std::size_t q = 0; q < elems_.size(); ++q) {
    const Index e = elems_[q], i = f.elem0[e];
    after += springEnergy(f, e);
    const Vec3 dF = springForce(f, e) - forceBefore_[q];  // on node i; its opposite on node i + 1
    const Vec3 v0 = f.invMass[i] > 0 ? f.vel[i] : Vec3::Zero(), v1 = f.invMass[i + 1] > 0 ? f.vel[i + 1] : Vec3::Zero();
    drift += 0.5 * dt * dF.dot(v0 - v1);
  }
  return after - before + drift;
}

}  // namespace woven
