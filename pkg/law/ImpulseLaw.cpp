#include "law/ImpulseLaw.hpp"
#include "core/Parallel.hpp"
#include "geom/GapFunction.hpp"
#include "fabric/SpringEnergy.hpp"
#include <algorithm>
#include <chrono>
#include <cmath>

namespace woven {

namespace {
// A row's layout is its contact's stencil (GapFunction's contactStencil): A's nodes with negative
// weights, B's with positive (vn = (vB - vA).n); four for a CP pair, two to eight for a persistent
// crossing.
inline Vec3 relativeVelocity(const Fabric& f, const Index* node, const Real* w, int n) {
  Vec3 v = w[0] * f.vel[node[0]];
  for (int k = 1; k < n; ++k) v += w[k] * f.vel[node[k]];
  return v;
}
inline void applyImpulse(Fabric& f, const Index* node, const Real* w, int n, const Vec3& J) {
  for (int k = 0; k < n; ++k) f.vel[node[k]] += (w[k] * f.invMass[node[k]]) * J;
}
}  // namespace

Vec3 ImpulseLaw::rowVelocity(const Fabric& f, const Row& r) const {
  Vec3 v = relativeVelocity(f, r.node, r.w, r.n);
  if (r.body >= 0) {
    const BodyVelocity& b = bodyVel_[r.body];
    v += b.v + b.w.cross(r.arm);
  }
  return v;
}

void ImpulseLaw::applyRow(Fabric& f, const Row& r, const Vec3& J) {
  applyImpulse(f, r.node, r.w, r.n, J);
  if (r.body >= 0) {
    BodyVelocity& b = bodyVel_[r.body];
    b.v += b.invM * J;
    b.w += b.invI * r.arm.cross(J);
  }
}

void ImpulseLaw::loadBodies(const std::vector<RigidBody>* bodies, Real bodyFriction) {
  bodyVel_.clear();
  if (!bodies) return;
  for (const RigidBody& b : *bodies)
    bodyVel_.push_back({b.vel, b.angVel, b.invMass(), b.invInertiaWorld(), b.kineticEnergy(), b.vel,
                        b.dynamic() ? Vec3(0.5 * b.hostKick) : Vec3(Vec3::Zero()), b.friction >= 0 ? b.friction : bodyFriction});
}

Real ImpulseLaw::storeBodies(std::vector<RigidBody>* bodies, bool afterDrift) {
  if (!bodies) return 0;
  Real work = 0;
  for (std::size_t k = 0; k < bodies->size(); ++k) {
    RigidBody& b = (*bodies)[k];
    if (!b.dynamic()) continue;
    b.vel = bodyVel_[k].v, b.angVel = bodyVel_[k].w;
    work += bodyVel_[k].ke0 - b.kineticEnergy();
    // At the synchronised velocity v -/+ hostKick/2 (before / after the drift, as energyChange's v_n
    // and v_{n+1}) the kinetic energy changes by M (v -/+ hostKick/2).dv + M dv^2/2: the half-step
    // change above and -/+ M hostKick/2 . dv (0 without a host kick: the same bits as before it).
    const Vec3& h = bodyVel_[k].halfKick;
    if (h.squaredNorm() > 0) work += (afterDrift ? -1.0 : 1.0) * b.mass * h.dot(bodyVel_[k].v - bodyVel_[k].v0);
  }
  // A kinematic body gives the fabric its impulse times its own velocity at the point (a scan of
  // every row, made only when there is one).
  if (std::all_of(bodies->begin(), bodies->end(), [](const RigidBody& b) { return b.dynamic(); })) return work;
  for (const Row& r : rows_)
    if (r.body >= 0 && !(*bodies)[r.body].dynamic()) {
      const BodyVelocity& b = bodyVel_[r.body];
      work += -(r.lambda * r.normal + r.lambdaT).dot(b.v + b.w.cross(r.arm));
    }
  return work;
}

void ImpulseLaw::resolve(Fabric& f, const std::vector<CPContact>& contacts, const Capacity& capacity, Real dt,
                         const ContactParams& p, ImpulseReport& rep, const std::vector<BodyContact>& bodyContacts,
                         std::vector<RigidBody>* bodies, Real horizon, const std::uint8_t* only) {
  rep = ImpulseReport{};
  const Real H = horizon > 0 ? horizon : dt;  // the drift the rooms are shared over
  // The solve's own tolerance: a miss that errs the drift by at most solverTolerance [m] (and never
  // below Eq. 4's band). The gap model only: its targets take a miss back at the next step (the gap
  // is measured again); the paper model's are the band alone, so a miss stays in the motion (the
  // pull-out's balance went from 0.65 % to 2 % with it).
  solverTol_ = p.model == ContactModel::Gap ? std::max(p.tolerance, p.solverTolerance / H) : p.tolerance;
  loadBodies(bodies, p.bodyFriction);
  // Which contacts need a row and their rows, each contact on its own (threads; the capacity is the
  // costly part and reads nothing the rows change); then the body rows, one by one.
  const Index nc = static_cast<Index>(contacts.size());
  slots_.resize(contacts.size());
  hasRow_.resize(contacts.size());
  // Model Gap: a row for every listed contact (the multiplier's sign decides); one that does not
  // approach beyond its gap at the start gets the gap as its room (its flattening capacity is not
  // measured: the row then stops it at the gap if other rows push it on).
  const bool everyContact = p.model == ContactModel::Gap;
  parallelFor(nc, 256, threads(), [&](Index c) {
    Row& r = slots_[c];
    hasRow_[c] = 0;
    if (only && !only[c]) return;
    r.n = contactStencil(f, contacts[c], r.node, r.w);
    r.normal = contacts[c].normal;
    r.vn0 = relativeVelocity(f, r.node, r.w, r.n).dot(r.normal);
    // Approach the room absorbs: the gap, and what flattening can still take, unless the contact is
    // still overlapping after the flattening passes (flattening has stopped working for it).
    const Real gap = contacts[c].gap - contacts[c].drift;
    Real allowed = std::max(gap, Real(0)) / H;
    if (r.vn0 < -allowed - p.tolerance) {  // neither separating, resting (Eq. 4), nor within the gap
      allowed = (gap < 0 ? 0.0 : gap + capacity(contacts[c])) / H;
      if (!everyContact && !(r.vn0 < -allowed - p.tolerance)) return;  // taken up by flattening
    } else if (!everyContact) {
      return;
    }
    Real K = 0;
    for (int k = 0; k < r.n; ++k) K += r.w[k] * r.w[k] * f.invMass[r.node[k]];
    if (!(K > 0)) return;  // both CPs kinematic
    r.invK = 1 / K;
    r.target = -allowed;
    // A persistent crossing's row starts from its last impulse (the warm start; applied below).
    r.lambda = contacts[c].warm > 0 ? contacts[c].warm : 0.0, r.lambdaT.setZero(), r.body = -1, r.arm.setZero();
    r.kick.setZero(), r.contact = c;
    hasRow_[c] = 1;
  });
  yarnRows_.clear();
  for (Index c = 0; c < nc; ++c)
    if (hasRow_[c]) yarnRows_.push_back(c);
  bodyRows_.clear();
  for (const BodyContact& c : bodyContacts) {
    Row r;
    r.lambda = 0, r.lambdaT.setZero(), r.kick.setZero(), r.contact = -1;
    r.node[0] = f.elem0[c.cp], r.node[1] = r.node[0] + 1, r.n = 2;
    r.w[0] = -(1 - c.s), r.w[1] = -c.s;
    r.normal = c.normal;
    r.body = c.body;
    r.arm = c.point - (*bodies)[c.body].pos;
    r.vn0 = rowVelocity(f, r).dot(r.normal);
    const Real allowed = std::max(c.gap, Real(0)) / H;
    if (!everyContact && !(r.vn0 < -allowed - p.tolerance)) continue;
    const BodyVelocity& b = bodyVel_[c.body];
    const Vec3 rn = r.arm.cross(r.normal);
    Real K = b.invM + rn.dot(b.invI * rn);
    for (int k = 0; k < 2; ++k) K += r.w[k] * r.w[k] * f.invMass[r.node[k]];
    if (!(K > 0)) continue;  // kinematic CP and body
    r.invK = 1 / K;
    r.target = -allowed;
    bodyRows_.push_back(r);
  }
  const Index nYarn = static_cast<Index>(yarnRows_.size());
  rep.rows = static_cast<long>(nYarn + bodyRows_.size());
  if (rep.rows == 0) {
    rows_.clear();
    return;
  }
  // The rows in contact order, then the body rows: coloured, and laid out by colour in rows_.
  // Sequential order: that list itself, made of the slots in place (the contacts with a row moved
  // forward, most often none) and swapped in, not copied row by row (a row is 192 bytes: the copy
  // was 3 % of the default impact). The same rows in the same order.
  if (p.sweepOrder != SweepOrder::Sequential) {
    colourRows(f, static_cast<Index>(rep.rows), p.sweepOrder,
               [&](Index r) -> const Row& { return r < nYarn ? slots_[yarnRows_[r]] : bodyRows_[r - nYarn]; });
  } else {
    for (Index r = 0; r < nYarn; ++r)
      if (yarnRows_[r] != r) slots_[r] = slots_[yarnRows_[r]];  // yarnRows_[r] >= r: forward, in place
    slots_.resize(static_cast<std::size_t>(nYarn));
    slots_.insert(slots_.end(), bodyRows_.begin(), bodyRows_.end());
    rows_.swap(slots_);
    serialLayout(static_cast<Index>(rows_.size()));
  }

  // The nodes the rows touch, each once, in the order the rows first reach them (a mark per node:
  // linear, where sorting the list cost 3 % of a ballistic step).
  touched_.clear();
  marked_.resize(f.nNodes(), 0);
  for (const Row& r : rows_)
    for (int k = 0; k < r.n; ++k)
      if (!marked_[r.node[k]]) marked_[r.node[k]] = 1, touched_.push_back(r.node[k]);
  for (Index i : touched_) marked_[i] = 0;
  dt_ = dt;
  keepVelocities(f);

  const bool friction = p.friction > 0 || p.bodyFriction > 0 ||
                        std::any_of(bodyVel_.begin(), bodyVel_.end(), [](const BodyVelocity& b) { return b.friction > 0; });
  if (friction) {
    // the row's half kick: its nodes' (forces and the body acceleration of the free ones) and, on a
    // body row, the body's (half its host kick); less half the row's velocity before the solve (header)
    const Vec3 hg = 0.5 * dt * f.bodyAcceleration;
    parallelFor(static_cast<Index>(rows_.size()), kRowGrain, threads(), [&](Index k) {
      Row& r = rows_[k];
      r.kick = -0.5 * rowVelocity(f, r);
      for (int q = 0; q < r.n; ++q) r.kick += (0.5 * dt * r.w[q] * f.invMass[r.node[q]]) * f.force[r.node[q]];
      if (hg.squaredNorm() > 0)
        for (int q = 0; q < r.n; ++q) r.kick += (f.invMass[r.node[q]] > 0 ? r.w[q] : 0.0) * hg;
      if (r.body >= 0 && bodyVel_[r.body].halfKick.squaredNorm() > 0) r.kick += bodyVel_[r.body].halfKick;
    });
  }
  // Warm start (Catto; Box2D): the rows of persistent crossings apply their last step's impulse
  // before the sweeps, which then correct it (lambda >= 0 accumulated as from 0). In row order, one
  // thread: a node's sum of impulses in a fixed order. After the friction's kick, which reads the
  // velocities before the solve.
  for (const Row& r : rows_)
    if (r.lambda > 0) applyRow(f, r, r.lambda * r.normal);
  rep.iterations = solve(f, p, friction);
  rep.skipped = skipped_;
  if (friction)  // the final tangential impulses against the mean slip (header), in row order
    for (const Row& r : rows_) rep.frictionWork -= r.lambdaT.dot(0.5 * rowVelocity(f, r) - r.kick);
  parallelFor(static_cast<Index>(rows_.size()), kRowGrain, threads(), [&](Index k) {
    const Row& r = rows_[k];
    const Real vn = rowVelocity(f, r).dot(r.normal);
    miss_[k] = r.lambda > 0 ? std::abs(vn - r.target) : r.target - vn;
  });
  // The largest miss and the rows missing by more than the tolerance, per fixed chunk (a maximum and
  // a count: exact in any order).
  struct Misses {
    Real worst = 0;
    long over = 0, overBand = 0;
    Misses& operator+=(const Misses& o) {
      return worst = std::max(worst, o.worst), over += o.over, overBand += o.overBand, *this;
    }
  };
  const Misses misses = chunkedSum(static_cast<Index>(miss_.size()), 4096, threads(), Misses{}, [&](Index k0, Index k1) {
    Misses m;
    for (Index k = k0; k < k1; ++k)
      m.worst = std::max(m.worst, miss_[k]), m.over += miss_[k] > solverTol_, m.overBand += miss_[k] > p.tolerance;
    return m;
  });
  rep.residual = misses.worst, rep.unresolved = misses.over, rep.unresolvedBand = misses.overBand;
  rep.energyChange = energyChange(f, false);
  rep.bodyWork = storeBodies(bodies, false);
}

void ImpulseLaw::contactImpulses(std::size_t contacts, std::vector<Real>& out) const {
  out.assign(contacts, 0.0);
  for (const Row& r : rows_)
    if (r.contact >= 0 && static_cast<std::size_t>(r.contact) < contacts) out[r.contact] = r.lambda;
}

void ImpulseLaw::keepVelocities(const Fabric& f) {
  vBefore_.resize(touched_.size());
  parallelFor(static_cast<Index>(touched_.size()), kParallelGrain, threads(), [&](Index k) { vBefore_[k] = f.vel[touched_[k]]; });
}

// The impulses change v_{n+1/2} by dv, which is v_n + (dt/2) a_n: the kinetic energy of step n
// changes by m (v_n . dv + dv^2 / 2). (Measured on v_{n+1/2} instead, a resting contact under load,
// whose impulse takes back each step the velocity the kick gave, would book (m/2)(a dt)^2 of
// dissipation every step that the motion never had.) a_n is the node's force over its mass and the
// body acceleration (gravity, Fabric::bodyAcceleration): with the forces' part alone a contact
// holding a node up against gravity booked (m/2)(g dt)^2 a step (tests/cpp/test_gravity_books).
// Internal rows (every node free) change no momentum, so the gravity term cancels over their nodes;
// it counts on rows against a body or a kinematic node.
// The restitution pass comes after the drift: its dv misses x_{n+1} and first shows in step n+1's
// kinetic energy, at v_{n+1} = v_{n+1/2} + (dt/2) a_{n+1}, taken as v_{n+1/2} + (dt/2) a_n (its
// forces are not yet known; the difference is O(dt^2)). Measured at v_n instead, the books lost
// m dv . a dt a step: in the 12.7 mm ballistic ply with e = 0.5 a balance error of -1.6 % at
// 0.7 dt_crit and -0.8 % at 0.35 (first order in dt).
Real ImpulseLaw::energyChange(const Fabric& f, bool afterDrift) const {
  const Real half = (afterDrift ? 0.5 : -0.5) * dt_;
  const Vec3 hg = half * f.bodyAcceleration;
  const bool gravity = hg.squaredNorm() > 0;  // without: the same operations as with no gravity term
  return chunkedSum(static_cast<Index>(touched_.size()), 4096, threads(), Real(0), [&](Index k0, Index k1) {
    Real dE = 0;
    for (Index k = k0; k < k1; ++k) {
      const Index i = touched_[k];
      if (f.invMass[i] == 0) continue;
      const Vec3 dv = f.vel[i] - vBefore_[k];
      Vec3 vn = vBefore_[k] + (half * f.invMass[i]) * f.force[i];
      if (gravity) vn += hg;
      dE += f.mass[i] * (vn.dot(dv) + 0.5 * dv.squaredNorm());
    }
    return dE;
  });
}

// No colours: the n rows of rows_ are all the serial tail, solved in order.
void ImpulseLaw::serialLayout(Index n) {
  std::fill(start_, start_ + RowColouring::kColours + 1, Index(0));
  start_[RowColouring::kColours + 1] = n;
  colours_ = blocks_ = 0;
}

// The rows by colour (law/RowColouring: rows of one colour share no node) or by block
// (law/RowBlocks: rows of two blocks share no node), the body rows last, laid out in that order in
// rows_ (rowAt(r): row r of the list, which rows_ must not hold): the sweeps then solve each
// colour's rows at once on the threads (or each phase's blocks at once, each in order), then the
// tail (the seam and the body rows) one by one. SweepOrder::Sequential: every row in the serial
// tail, in list order.
template <class RowAt>
void ImpulseLaw::colourRows(const Fabric& f, Index n, SweepOrder order, RowAt&& rowAt) {
  rows_.resize(static_cast<std::size_t>(n));
  if (order == SweepOrder::Sequential) {  // the serial tail alone, in list order: nothing to colour
    parallelFor(n, kParallelGrain, threads(), [&](Index k) { rows_[k] = rowAt(k); });
    serialLayout(n);
    return;
  }
  const auto nodesOf = [&](Index r, Index* node) {
    const Row& q = rowAt(r);
    if (q.body >= 0) return -1;  // all of a body's rows share it
    for (int k = 0; k < q.n; ++k) node[k] = q.node[k];
    return q.n;
  };
  if (order == SweepOrder::Blocked) {
    blocking_.build(n, f.pos, nodesOf);
    parallelFor(n, kParallelGrain, threads(), [&](Index k) { rows_[k] = rowAt(blocking_.order()[k]); });
    std::fill(start_, start_ + RowColouring::kColours + 2, n);
    for (int g = 0; g <= RowBlocks::kSeam; ++g) start_[g] = blocking_.begin(g);
    start_[RowColouring::kColours] = blocking_.begin(RowBlocks::kSeam);  // the seam, then the body rows
    colours_ = 0, blocks_ = RowBlocks::kBlocks;
    return;
  }
  colouring_.build(n, f.nNodes(), nodesOf);
  parallelFor(n, kParallelGrain, threads(), [&](Index k) { rows_[k] = rowAt(colouring_.order()[k]); });
  for (int c = 0; c <= RowColouring::kColours + 1; ++c) start_[c] = colouring_.begin(c);
  colours_ = colouring_.colours(), blocks_ = 0;
}

// One Gauss-Seidel update of row r (projected on J >= 0 and the friction cone); returns how far the
// row missed its target before it (below it, or above it while still pushing: the accumulated
// impulse can give back) [m/s].
Real ImpulseLaw::solveRow(Fabric& f, Row& r, const ContactParams& p, bool friction) {
  const Vec3 vr = rowVelocity(f, r);
  const Real vn = vr.dot(r.normal);
  const Real miss = r.lambda > 0 ? std::abs(vn - r.target) : r.target - vn;
  const Real lambda = std::max(r.lambda + (r.target - vn) * r.invK, Real(0));
  Vec3 J = (lambda - r.lambda) * r.normal;
  r.lambda = lambda;
  const Real mu = r.body < 0 ? p.friction : bodyVel_[r.body].friction;
  Vec3 Jt = Vec3::Zero();
  if (friction && mu > 0) {  // Coulomb: cancel the tangential slip, within the cone mu * lambda
    const Vec3 vt = vr - vn * r.normal;
    Vec3 lt = r.lambdaT - vt * r.invK;
    const Real lim = mu * r.lambda, len = lt.norm();
    if (len > lim) lt *= lim / len;
    Jt = lt - r.lambdaT;
    J += Jt;
    r.lambdaT = lt;
  }
  applyRow(f, r, J);
  return miss;
}

// solveRow's update of a row on no body while friction between yarns is off, in the same operations:
// the same bits (measured: the scenes' figures unchanged to the last digit).
[[gnu::always_inline]] inline Real ImpulseLaw::solveRow(Fabric& f, SweepRow& r) {
  const Real vn = relativeVelocity(f, r.node, r.w, r.n).dot(r.normal);
  const Real miss = r.lambda > 0 ? std::abs(vn - r.target) : r.target - vn;
  const Real lambda = std::max(r.lambda + (r.target - vn) * r.invK, Real(0));
  const Vec3 J = (lambda - r.lambda) * r.normal;
  r.lambda = lambda;
  applyImpulse(f, r.node, r.w, r.n, J);
  return miss;
}

// Coloured sweeps: the colours in order, each colour's rows on the threads (they share no node:
// each writes only its own nodes, so any split gives the same bits), then the serial tail (the
// rows on a body) in order. Blocked sweeps: the blocks at once, each block's rows in order (blocks
// share no node), then the cuts' rows in two phases, then the tail (the seam, then the rows on a
// body) in order. The misses are kept per row; their largest is order-free.
// Whether the colours are split over the threads changes no result, only the time: a sweep costs
// a barrier per colour, and on cores busy with other processes each barrier waits for a thread
// that is not running (measured, bench_threads at a load of 3-13 on 2 cores: the response phase
// 8-13x slower on 2 threads than on 1 with every sweep split). So the first sweep of a step runs
// split and the second on one thread, both timed, and the rest of the step's sweeps as the faster.
int ImpulseLaw::solve(Fabric& f, const ContactParams& p, bool friction) {
  using Clock = std::chrono::steady_clock;
  const int nThreads = threads();
  miss_.resize(rows_.size());
  double seconds[2] = {0, 0};  // of the split sweep and of the one-thread sweep
  // Without friction between yarns the rows are swept packed (SweepRow; the rows on a body as they
  // are), their impulses copied back after.
  const bool packed = !(p.friction > 0);
  const Index nRows = static_cast<Index>(rows_.size());
  if (packed) {
    packed_.resize(rows_.size());
    parallelFor(nRows, kParallelGrain, nThreads, [&](Index k) {
      const Row& r = rows_[k];
      SweepRow& q = packed_[k];
      for (int i = 0; i < r.n; ++i) q.node[i] = r.node[i], q.w[i] = r.w[i];
      q.n = r.n, q.normal = r.normal, q.target = r.target, q.invK = r.invK, q.lambda = r.lambda, q.body = r.body >= 0;
    });
  }
  // The active set (below). Its rows: the serial tail's (sequential and coloured orders), or the
  // blocks' (blocked order; the cuts' and the tail's rows are then updated every sweep). Each of its
  // regions (the tail, or a block) has its own words of the bit sets, so the threads that solve the
  // blocks at once, or the cuts of a phase (each cut wakes only the two blocks beside it), never
  // write the same word.
  const Index tailStart = start_[RowColouring::kColours];
  const bool blocked = blocks_ > 0;
  const int regions = blocked ? blocks_ : 1;
  Index tracked = 0;  // rows in the active set
  {
    Index bits = 0;
    for (int g = 0; g < regions; ++g) {
      const Index r0 = blocked ? start_[g] : tailStart, r1 = blocked ? start_[g + 1] : nRows;
      region_[g] = {r0, r1, bits};
      bits += (r1 - r0 + 63) / 64 * 64;
      tracked += r1 - r0;
    }
    bitCount_ = bits;
  }
  const auto nodesOfRow = [&](Index k, const Index*& node) {
    if (packed && !packed_[k].body) return node = packed_[k].node, packed_[k].n;
    return node = rows_[k].node, rows_[k].n;
  };
  // Each node's rows of the active set (CSR, as bits), in bit order.
  nodeStart_.assign(f.pos.size() + 1, 0);
  for (int g = 0; g < regions; ++g)
    for (Index k = region_[g].row0; k < region_[g].row1; ++k) {
      const Index* node;
      for (int q = 0, n = nodesOfRow(k, node); q < n; ++q) ++nodeStart_[node[q] + 1];
    }
  for (std::size_t i = 1; i < nodeStart_.size(); ++i) nodeStart_[i] += nodeStart_[i - 1];
  nodeRows_.resize(static_cast<std::size_t>(nodeStart_.back()));
  fill_.assign(nodeStart_.begin(), nodeStart_.end() - 1);
  for (int g = 0; g < regions; ++g)
    for (Index k = region_[g].row0; k < region_[g].row1; ++k) {
      const Index* node;
      for (int q = 0, n = nodesOfRow(k, node); q < n; ++q) nodeRows_[fill_[node[q]]++] = region_[g].bit0 + k - region_[g].row0;
    }
  // The same lists as words of the bit sets: each node's rows (listed in order) grouped by their
  // 64-row word, an OR mask per word. An update wakes its nodes' rows a word at a time (one
  // read-modify-write of a set per word, where one per row was a third of the sweeps' time: stores
  // to one word in a chain).
  wordStart_.resize(nodeStart_.size());
  words_.clear(), masks_.clear();
  for (std::size_t v = 0; v + 1 < nodeStart_.size(); ++v) {
    wordStart_[v] = static_cast<Index>(words_.size());
    for (Index j = nodeStart_[v]; j < nodeStart_[v + 1]; ++j) {
      const Index w = nodeRows_[j] >> 6;
      if (static_cast<Index>(words_.size()) == wordStart_[v] || words_.back() != w) words_.push_back(w), masks_.push_back(0);
      masks_.back() |= std::uint64_t(1) << (nodeRows_[j] & 63);
    }
  }
  wordStart_.back() = static_cast<Index>(words_.size());
  // The tail's rows on a body (updated every sweep), once rather than a scan of the tail per sweep.
  tailBodies_.clear();
  if (!blocked)
    for (Index k = tailStart; k < nRows; ++k)
      if (packed ? packed_[k].body : rows_[k].body >= 0) tailBodies_.push_back(k - tailStart);
  // Every row of the active set to be updated in the first sweep (the words' padding never).
  dirty_.assign(static_cast<std::size_t>(bitCount_ / 64), 0);
  for (int g = 0; g < regions; ++g) {
    const Region& q = region_[g];
    for (Index j = 0; j < q.row1 - q.row0; ++j) dirty_[(q.bit0 + j) >> 6] |= std::uint64_t(1) << ((q.bit0 + j) & 63);
  }
  next_.assign(dirty_.size(), 0);
  skipped_ = 0;
  std::fill(miss_.begin(), miss_.end(), Real(0));
  // One update of row k; true when it changed the row's impulse by more than the wake threshold.
  // An update that moved the row's velocity by less than the tolerance (kWake) wakes none of its
  // neighbours: it moves theirs by less (a node's share of it), and they stay within the tolerance
  // unless several such updates add up (the final misses are measured, not assumed).
  const auto update = [&](Index k) {
    const bool onBody = packed ? packed_[k].body : rows_[k].body >= 0;
    const bool fast = packed && !onBody;
    const Real before = fast ? packed_[k].lambda : rows_[k].lambda;
    const Vec3 beforeT = packed ? Vec3::Zero() : rows_[k].lambdaT;
    miss_[k] = fast ? solveRow(f, packed_[k]) : solveRow(f, rows_[k], p, friction);
    const Real dLambda = std::abs((fast ? packed_[k].lambda : rows_[k].lambda) - before);
    const Real invK = fast ? packed_[k].invK : rows_[k].invK;
    return dLambda > kWake * solverTol_ * invK ||
           (!packed && (rows_[k].lambdaT - beforeT).norm() > kWake * solverTol_ * invK);
  };
  // Row k's update woke the active set's rows of its nodes: with `own` its bit (a row of the set),
  // the later ones in this sweep and the earlier ones in the next; without (-1: a cut's or the tail's
  // row beside the blocks, which come first in a sweep), all in the next.
  const auto wake = [&](Index k, Index own) {
    const Index ownWord = own >= 0 ? own >> 6 : -1;
    const std::uint64_t ownBit = own >= 0 ? std::uint64_t(1) << (own & 63) : 0, earlier = ownBit - 1,
                        later = ~(earlier | ownBit);
    const Index* node;
    for (int q = 0, n = nodesOfRow(k, node); q < n; ++q)
      for (Index j = wordStart_[node[q]]; j < wordStart_[node[q] + 1]; ++j) {
        const Index w = words_[j];
        const std::uint64_t m = masks_[j];
        if (own < 0 || w < ownWord) next_[w] |= m;
        else if (w > ownWord) dirty_[w] |= m;
        else dirty_[w] |= m & later, next_[w] |= m & earlier;
      }
  };
  // The rows of region g marked in dirty_ (cleared as taken), in order: updated, their misses'
  // largest into worst, whether an update woke a row into wroteAny; returns how many.
  const auto sweepRegion = [&](int g, Real& worst, bool& wroteAny) {
    const Region& q = region_[g];
    Index updated = 0;
    for (Index word = q.bit0 >> 6, end = (q.bit0 + q.row1 - q.row0 + 63) >> 6; word < end; ++word)
      while (dirty_[word]) {
        const int bit = __builtin_ctzll(dirty_[word]);
        dirty_[word] &= dirty_[word] - 1;
        const Index own = word * 64 + bit, k = q.row0 + own - q.bit0;
        ++updated;
        if (update(k)) wake(k, own), wroteAny = true;
        worst = std::max(worst, miss_[k]);
      }
    return updated;
  };
  int sweeps = p.maxIterations;
  for (int it = 0; it < p.maxIterations; ++it) {
    const bool split = nThreads > 1 && (it == 0 || (it > 1 && seconds[0] <= seconds[1]));
    const auto t0 = Clock::now();
    // The active set: a row no other row has changed a node of since its own last update would only
    // repeat it (its miss was taken to its target, or it separates): it is skipped, its miss 0. An
    // update that changes velocities marks the rows of its nodes (those after it in this sweep,
    // those before in the next); the rows on a body (they share its velocities) are updated every
    // sweep.
    if (it > 0) {
      dirty_.swap(next_);
      for (const Index r : tailBodies_) dirty_[r >> 6] |= std::uint64_t(1) << (r & 63);
      std::fill(next_.begin(), next_.end(), 0);
    }
    Index updated = 0;
    bool wroteAny = false;
    // Blocks, then the rows across the even cuts, then the odd cuts': the groups of a phase each on
    // a thread, its rows in order (law/RowBlocks); a block's rows from the active set, the cuts'
    // every one. Each group's largest miss, update count and wake kept by its thread (a maximum, a
    // sum, an or: the same in any order).
    Real groupWorst[RowBlocks::kSeam] = {};
    Index groupUpdated[RowBlocks::kSeam] = {};
    bool groupWrote[RowBlocks::kSeam] = {};
    for (int phase = 0; blocked && phase < RowBlocks::kPhases; ++phase) {
      const int g0 = RowBlocks::phaseBegin(phase);
      parallelFor(RowBlocks::phaseBegin(phase + 1) - g0, 1, split ? nThreads : 1, [&](Index q) {
        const int g = g0 + static_cast<int>(q);
        if (phase == 0) {
          groupUpdated[g] = sweepRegion(g, groupWorst[g], groupWrote[g]);
          return;
        }
        for (Index k = start_[g]; k < start_[g + 1]; ++k) {
          if (update(k)) wake(k, -1), groupWrote[g] = true;
          groupWorst[g] = std::max(groupWorst[g], miss_[k]);
        }
      });
    }
    for (int c = 0; c < colours_; ++c) {
      const Index b = start_[c];
      if (packed)
        parallelFor(start_[c + 1] - b, kRowGrain, split ? nThreads : 1,
                    [&](Index k) { miss_[b + k] = solveRow(f, packed_[b + k]); });
      else
        parallelFor(start_[c + 1] - b, kRowGrain, split ? nThreads : 1,
                    [&](Index k) { miss_[b + k] = solveRow(f, rows_[b + k], p, friction); });
    }
    if (it < 2) seconds[it] = std::chrono::duration<double>(Clock::now() - t0).count();
    Real worst = 0;
    if (blocked) {
      for (int g = 0; g < RowBlocks::kSeam; ++g)
        worst = std::max(worst, groupWorst[g]), updated += g < blocks_ ? groupUpdated[g] : 0, wroteAny |= groupWrote[g];
      // The tail (the seam, then the rows on a body), every row, in order.
      for (Index k = tailStart; k < nRows; ++k) {
        if (update(k)) wake(k, -1), wroteAny = true;
        worst = std::max(worst, miss_[k]);
      }
    } else {
      for (Index k = 0; k < tailStart; ++k) worst = std::max(worst, miss_[k]);  // the colours' rows
      updated = sweepRegion(0, worst, wroteAny);
    }
    skipped_ += tracked - updated;
    // Nothing left to update: every row as its last update left it (sequential and coloured: no
    // row of the tail was marked; blocked: no update in the sweep woke a row).
    if ((!blocked && tailStart < nRows && updated == 0) || (blocked && !wroteAny)) {
      sweeps = it + 1;
      break;
    }
    if (worst <= solverTol_) {
      sweeps = it + 1;
      break;
    }
  }
  if (packed)
    parallelFor(nRows, kParallelGrain, nThreads, [&](Index k) {
      if (!packed_[k].body) rows_[k].lambda = packed_[k].lambda;
    });
  return sweeps;
}

Real ImpulseLaw::restitute(Fabric& f, const ContactParams& p, std::vector<RigidBody>* bodies, Real* bodyWork) {
  if (p.restitution == 0 || rows_.empty()) return 0;
  loadBodies(bodies, p.bodyFriction);
  std::size_t kept = 0;
  for (const Row& r : rows_) {
    if (!(r.lambda > 0 && r.vn0 < -p.tolerance)) continue;
    Row q = r;
    q.target = -p.restitution * r.vn0;
    q.lambda = 0, q.lambdaT.setZero();
    rows_[kept++] = q;
  }
  rows_.resize(kept);
  sorted_.swap(rows_);
  colourRows(f, static_cast<Index>(kept), p.sweepOrder, [&](Index r) -> const Row& { return sorted_[r]; });
  keepVelocities(f);
  solve(f, p, false);
  const Real work = storeBodies(bodies, true);
  if (bodyWork) *bodyWork += work;
  return energyChange(f, true);
}

Real ImpulseLaw::correctPositions(Fabric& f, const std::vector<CPContact>& contacts, const ContactParams& p) {
  if (p.positionCorrection == 0) return 0;
  // The CPs whose length the correction can change: those of the nodes it moves.
  std::vector<Index> elems;
  for (const CPContact& c : contacts) {
    if (!(c.gap < -p.correctionSlop && c.sectional)) continue;
    for (Index e : {c.cpA, c.cpB})
      for (Index k = std::max(e - 1, 0); k <= std::min(e + 1, f.nElems() - 1); ++k)
        if (f.elemYarn[k] == f.elemYarn[e]) elems.push_back(k);
  }
  if (elems.empty()) return 0;
  std::sort(elems.begin(), elems.end());
  elems.erase(std::unique(elems.begin(), elems.end()), elems.end());
  Real before = 0, after = 0;
  for (Index e : elems) before += springEnergy(f, e);
  for (const CPContact& c : contacts) {
    if (!(c.gap < -p.correctionSlop && c.sectional)) continue;
    Index node[kMaxStencil];
    Real w[kMaxStencil], K = 0;
    contactStencil(f, c, node, w);  // a CP pair of the paper's model: its four nodes
    for (int k = 0; k < 4; ++k) K += w[k] * w[k] * f.invMass[node[k]];
    if (!(K > 0)) continue;
    const Vec3 d = (p.positionCorrection * (-c.gap - p.correctionSlop) / K) * c.normal;  // relative shift along n
    // Each node moves across its own CP only: a shift along a yarn of stiffness E A / l0 stores
    // (1/2) K dx^2 at once (measured: 0.06 um per step on nearly parallel yarns put in three times the
    // drop's kinetic energy), while one across it stretches the CP only to second order.
    const Vec3 tA = (f.pos[node[1]] - f.pos[node[0]]).normalized(), tB = (f.pos[node[3]] - f.pos[node[2]]).normalized();
    for (int k = 0; k < 4; ++k) {
      const Vec3 dx = (w[k] * f.invMass[node[k]]) * d;
      const Vec3& t = k < 2 ? tA : tB;
      f.pos[node[k]] += dx - dx.dot(t) * t;
    }
  }
  for (Index e : elems) after += springEnergy(f, e);
  return after - before;
}

}  // namespace woven
