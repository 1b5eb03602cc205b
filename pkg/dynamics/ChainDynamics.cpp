#include "dynamics/ChainDynamics.hpp"
#include "core/Errors.hpp"
#include "core/Parallel.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

Real criticalTimeStep(const Fabric& f) {
  Real dt = INFINITY;
  for (Index e = 0; e < f.nElems(); ++e) {
    if (!f.alive[e] || f.stiffness[e] <= 0) continue;
    const Real me = f.elementMass(e), K = f.stiffness[e];
    const Real xi = f.damping[e] / std::sqrt(K * me);
    dt = std::min(dt, std::sqrt(me / K) * (std::sqrt(1 + xi * xi) - xi));
  }
  // Bending (bendingForces): about a straight chain the transverse stiffness is (k_b / l^2) D^T D, D
  // the second difference, whose largest eigenvalue is 16: omega^2 = 16 k_b / (m l^2) at a node of
  // mass m between elements of length l. Taken with the axial limit as 1/dt^2 = 1/dt_a^2 + omega^2 / 4
  // (the modes share the node): conservative, and the axial limit itself without bending.
  Real bend = 0;  // largest omega^2 / 4 [1/s^2]
  for (const Yarn& y : f.yarns) {
    const Real EI = f.materials[y.material].bending;
    if (!(EI > 0)) continue;
    for (Index k = 1; k + 1 < y.nNodes; ++k) {
      const Index i = y.firstNode + k, e = y.firstElem + k;
      if (f.invMass[i] == 0) continue;
      const Real l = std::min(f.restLength[e - 1], f.restLength[e]);
      const Real kb = 2 * EI / (f.restLength[e - 1] + f.restLength[e]);
      bend = std::max(bend, 4 * kb * f.invMass[i] / (l * l));
    }
  }
  return bend > 0 ? 1 / std::sqrt(1 / (dt * dt) + bend) : dt;
}

std::vector<std::uint8_t> slowElements(const Fabric& f, Real outerDt) {
  const Index nn = f.nNodes(), ne = f.nElems();
  std::vector<Real> sumK(nn, 0.0), factor(nn, 1.0);
  for (Index e = 0; e < ne; ++e) {
    if (!f.alive[e] || f.stiffness[e] <= 0) continue;
    const Real K = f.stiffness[e], xi = f.damping[e] / std::sqrt(K * f.elementMass(e));
    const Real fe = std::sqrt(1 + xi * xi) - xi;
    for (Index i : {f.elem0[e], f.elem0[e] + 1}) sumK[i] += K, factor[i] = std::min(factor[i], fe);
  }
  std::vector<std::uint8_t> slow(ne, 0);
  const auto stable = [&](Index i) {
    return f.invMass[i] == 0 || sumK[i] == 0 || std::sqrt(2 * f.mass[i] / sumK[i]) * factor[i] >= outerDt;
  };
  for (Index e = 0; e < ne; ++e)
    slow[e] = f.alive[e] && f.stiffness[e] > 0 && stable(f.elem0[e]) && stable(f.elem0[e] + 1);
  return slow;
}

ChainDynamics::ChainDynamics(Fabric& fabric) : f_(fabric), dtCrit_(criticalTimeStep(fabric)) {
  for (const YarnMaterial& m : f_.materials) bendingOn_ = bendingOn_ || m.bending > 0;
  for (Index i = 0; i < f_.nNodes(); ++i) mass_ += f_.mass[i];
}

void ChainDynamics::prescribeVelocity(Index i, const Vec3& v) {
  f_.checkNode(i);
  require(v.allFinite() && v.norm() <= 1e5, "velocity", v.norm(), "finite, |v| <= 1e5 m/s");
  auto it = std::find(loads_.kinematicNodes.begin(), loads_.kinematicNodes.end(), i);
  if (it == loads_.kinematicNodes.end()) {
    loads_.kinematicNodes.push_back(i);
    loads_.kinematicVelocity.push_back(v);
    loads_.reaction.push_back(Vec3::Zero());
  } else {
    loads_.kinematicVelocity[it - loads_.kinematicNodes.begin()] = v;
  }
  f_.invMass[i] = 0.0;
  f_.vel[i] = v;
}

void ChainDynamics::setVelocityRamp(Real seconds) {
  require(std::isfinite(seconds) && seconds >= 0 && seconds <= 1e6, "velocity_ramp", seconds, "[0, 1e6] s");
  loads_.velocityRamp = seconds;
}

void ChainDynamics::release(Index i) {
  f_.checkNode(i);
  auto it = std::find(loads_.kinematicNodes.begin(), loads_.kinematicNodes.end(), i);
  if (it == loads_.kinematicNodes.end()) return;
  const auto k = it - loads_.kinematicNodes.begin();
  loads_.kinematicNodes.erase(it);
  loads_.kinematicVelocity.erase(loads_.kinematicVelocity.begin() + k);
  loads_.reaction.erase(loads_.reaction.begin() + k);
  f_.invMass[i] = 1.0 / f_.mass[i];
}

void ChainDynamics::setPointForce(Index i, const Vec3& F) {
  f_.checkNode(i);
  require(F.allFinite() && F.norm() <= 1e9, "force", F.norm(), "finite, |F| <= 1e9 N");
  auto it = std::find(loads_.forceNodes.begin(), loads_.forceNodes.end(), i);
  if (it != loads_.forceNodes.end()) {
    const auto k = it - loads_.forceNodes.begin();
    loads_.forceNodes.erase(it);
    loads_.forceValues.erase(loads_.forceValues.begin() + k);
  }
  if (F.squaredNorm() > 0) {
    loads_.forceNodes.push_back(i);
    loads_.forceValues.push_back(F);
  }
  if (started_) refreshForces();
}

void ChainDynamics::configureBreakage(const BreakageParams& p) {
  p.validate();
  if (!started_) start();
  computeForces(0.0);  // strains of the current state: the filter starts from them
  breakage_.configure(f_, p);
  checkpoint();  // the last good state carries the new breakage state (restoreLastGood puts it back)
}

void ChainDynamics::setSlowElements(std::vector<std::uint8_t> slow, int m) {
  require(m >= 1 && m <= 64, "substeps", m, "[1, 64]");
  require(slow.empty() || static_cast<Index>(slow.size()) == f_.nElems(), "slow_elements", static_cast<double>(slow.size()),
          "empty or one flag per element (" + fmt(f_.nElems()) + ")");
  if (m == 1 || std::find(slow.begin(), slow.end(), 1) == slow.end()) slow.clear();
  const int rate = slow.empty() ? 1 : m;
  chainSteps_ = m;
  if (rate == rate_ && slow == slow_) return;
  slow_ = std::move(slow);
  rate_ = rate;
  if (!started_) return;
  // The force in f_.force serves the next kick's two halves: the last step's closing half, which
  // must keep the old weights, and the next step's opening half, which takes the new. Recompute it
  // with the new weights (the same positions and velocities: only the weights change) and give the
  // velocities the closing half's difference, (dt_prev / 2) (F_old - F_new) / m: the kick then closes
  // with the old force and opens with the new, and the synchronised velocity is unchanged.
  const Vec3Array old = f_.force;
  computeForces(0.0);  // the books take nothing at dt = 0
  for (Index i = 0; i < f_.nNodes(); ++i) f_.vel[i] += (0.5 * dtPrev_ * f_.invMass[i]) * (old[i] - f_.force[i]);
}

void ChainDynamics::setBodyAcceleration(const Vec3& g) {
  require(g.allFinite() && g.norm() <= 1e6, "gravity", g.norm(), "finite, |g| <= 1e6 m/s^2");
  loads_.bodyAcceleration = g;
  f_.bodyAcceleration = g;  // the impulse law's energy books read it there
}

Vec3 ChainDynamics::acceleration(Index i) const {
  const Real im = f_.invMass[i];
  return im > 0 ? Vec3(f_.force[i] * im + loads_.bodyAcceleration) : Vec3(Vec3::Zero());
}

Vec3 ChainDynamics::syncVelocity(Index i) const { return f_.vel[i] + 0.5 * dtPrev_ * acceleration(i); }

Vec3 ChainDynamics::reaction(const std::vector<Index>& nodes) const {
  Vec3 R = Vec3::Zero();
  for (Index i : nodes) {
    auto it = std::find(loads_.kinematicNodes.begin(), loads_.kinematicNodes.end(), i);
    if (it != loads_.kinematicNodes.end()) R += loads_.reaction[it - loads_.kinematicNodes.begin()];
  }
  return R;
}

void ChainDynamics::start() {
  computeForces(0.0);
  books_.damped = 0;
  books_.work = 0;
  books_.contact = 0;
  books_.friction = 0;
  books_.contactInput = 0;
  books_.released = 0;
  books_.projection = 0;
  books_.spring = 0;
  springSeen_ = false;
  books_.bodyWork = 0;
  Real ke = 0;
  for (Index i = 0; i < f_.nNodes(); ++i) ke += 0.5 * f_.mass[i] * f_.vel[i].squaredNorm();
  books_.kinetic = ke;
  books_.initial = ke + books_.elastic;
  started_ = true;
  checkpoint();
}

void ChainDynamics::refreshForces() {
  if (!started_) return start();
  computeForces(0.0);  // dt = 0: the damped and work books take nothing
}

namespace {
// Fixed chunks of the node and element loops (Parallel.hpp): their sums are the same bits at any
// thread count. Large enough that a chunk costs far more than its share of a parallel region.
constexpr Index kNodeChunk = 4096, kElemChunk = 2048;
struct KickSums {  // 2 x kinetic energy of step n, and sum m v_{n+1/2} of free nodes
  Real ke2 = 0;
  Vec3 p = Vec3::Zero();
  KickSums& operator+=(const KickSums& o) {
    ke2 += o.ke2, p += o.p;
    return *this;
  }
};
struct SpringSums {  // per chunk of CPs
  Real elastic = 0, dissipated = 0;
  SpringSums& operator+=(const SpringSums& o) {
    elastic += o.elastic, dissipated += o.dissipated;
    return *this;
  }
};
}  // namespace

// Kick and drift of every node (velocity Verlet with the two half-kicks of consecutive steps fused,
// see the header). Kinematic nodes have invMass 0 and had their velocity set before. Returns the
// kinetic energy of step n; momentum collects sum m v_{n+1/2} of free nodes for the body-force work.
// (A separate pass: fusing it into the CP loop below was measured slower, 39 vs 62 M node-steps/s
// in cache, because each CP then waits on the drift of its second node.) Nodes are independent;
// the sums are taken per fixed chunk of nodes.
template <bool Gravity, bool Drift>
Real ChainDynamics::kickDrift(Real dt, Vec3& momentum) {
  const Real hPrev = 0.5 * dtPrev_, h = 0.5 * dt;
  const Vec3 g = loads_.bodyAcceleration;
  Vec3* __restrict x = f_.pos.data();
  Vec3* __restrict v = f_.vel.data();
  const Vec3* __restrict F = f_.force.data();
  const Real* __restrict im = f_.invMass.data();
  const Real* __restrict m = f_.mass.data();
  const KickSums s = chunkedSum(f_.nNodes(), kNodeChunk, threads(), KickSums(), [&](Index i0, Index i1) {
    KickSums c;
    for (Index i = i0; i < i1; ++i) {
      Vec3 a = F[i] * im[i];
      if (Gravity) a += (im[i] > 0 ? 1.0 : 0.0) * g;
      const Vec3 vn = v[i] + hPrev * a;
      c.ke2 += m[i] * vn.squaredNorm();
      v[i] = vn + h * a;
      if (Drift) {
        if (Gravity) c.p += (im[i] > 0 ? m[i] : 0.0) * v[i];
        x[i] += dt * v[i];
      }
    }
    return c;
  });
  momentum = s.p;
  return 0.5 * s.ke2;
}

// The drift alone, after a StepHook changed the velocities.
template <bool Gravity>
void ChainDynamics::drift(Real dt, Vec3& momentum) {
  Vec3* __restrict x = f_.pos.data();
  const Vec3* __restrict v = f_.vel.data();
  const Real* __restrict im = f_.invMass.data();
  const Real* __restrict m = f_.mass.data();
  momentum = chunkedSum(f_.nNodes(), kNodeChunk, threads(), Vec3(Vec3::Zero()), [&](Index i0, Index i1) {
    Vec3 p = Vec3::Zero();
    for (Index i = i0; i < i1; ++i) {
      if (Gravity) p += (im[i] > 0 ? m[i] : 0.0) * v[i];
      x[i] += dt * v[i];
    }
    return p;
  });
}

// Discrete bending at each interior node k of a yarn whose two elements are whole: E_k = (k_b / 2)
// (theta_k - theta0_k)^2, theta_k the turn between the unit chords u = (x_k - x_{k-1}) / l_1 and w =
// (x_{k+1} - x_k) / l_2, theta0_k its turn as built (Fabric::restTurn: a weave starts stress-free and
// resists a change of its crimp), k_b = 2 EI / (l0_1 + l0_2): the beam's EI (kappa - kappa0)^2 / 2 over
// the node's share of the yarn with kappa = theta / l0 (a node-angle spring, Bergou et al.'s
// discrete elastic rods without twist). F = -dE/dx with theta = atan2(|u x w|, u.w): dtheta/dx =
// -(1/sin theta) dc/dx, c = u.w, dc/dx_{k-1} = -(w - c u) / l_1, dc/dx_{k+1} = (u - c w) / l_2, x_k
// taking minus their sum; a node turned by less than 1e-12 rad has no direction to be pushed in and
// takes no force. One thread, in node order (the same bits at any thread count). Returns the energy [J].
Real ChainDynamics::bendingForces() {
  Vec3* __restrict F = f_.force.data();
  const Vec3* __restrict x = f_.pos.data();
  Real energy = 0;
  for (const Yarn& y : f_.yarns) {
    const Real EI = f_.materials[y.material].bending;
    if (!(EI > 0)) continue;
    for (Index k = 1; k + 1 < y.nNodes; ++k) {
      const Index i = y.firstNode + k, e = y.firstElem + k;
      if (!f_.alive[e - 1] || !f_.alive[e]) continue;  // a broken end bends no further
      const Vec3 d1 = x[i] - x[i - 1], d2 = x[i + 1] - x[i];
      const Real l1 = d1.norm(), l2 = d2.norm();
      const Vec3 u = d1 / l1, w = d2 / l2;
      const Real c = u.dot(w), sn = u.cross(w).norm();
      const Real turn = std::atan2(sn, c) - f_.restTurn[i];
      const Real kb = 2 * EI / (f_.restLength[e - 1] + f_.restLength[e]);
      energy += 0.5 * kb * turn * turn;
      if (!(sn > 1e-12)) continue;
      const Real g = kb * turn / sn;
      const Vec3 Fa = -g * (w - c * u) / l1, Fb = g * (u - c * w) / l2;
      F[i - 1] += Fa, F[i + 1] += Fb, F[i] -= Fa + Fb;
    }
  }
  return energy;
}

// The axial spring + dashpot of every CP (paper Eq. 3): T = K(l - l0) + c*ldot along
// n = (x1-x0)/l, +T*n on the first node and -T*n on the second; tension-only yarns carry no force
// while slack and their dashpot never pushes (T = max(0, T)). Chains are contiguous, so each node's
// force is assigned by the element before it and completed by the element after it (no zeroing
// pass). Also the elastic energy and the dashpot dissipation, and with StoreElementState the strain
// and tension of each CP (left out of the step: the two stores cost ~14 % of its throughput).
// Threads take fixed chunks of CPs. A chunk's first CP does not add to its first node, which the
// chunk before assigns, but leaves its force in edge_; those are added after the loop, so each node
// sees the same two operations in the same order as in one pass: the same bits at any thread count.
template <bool StoreElementState>
void ChainDynamics::springForces(Real dt) {
  Vec3* __restrict F = f_.force.data();
  const Vec3* __restrict x = f_.pos.data();
  const Vec3* __restrict v = f_.vel.data();
  const Real* __restrict l0 = f_.restLength.data();
  const Real* __restrict K = f_.stiffness.data();
  const Real* __restrict C = f_.damping.data();
  Real* __restrict strain = f_.strain.data();
  Real* __restrict tension = f_.tension.data();
  // Multi-rate: a slow element's force enters with weight slowNow_ (setSlowElements); 1 x T is T,
  // so one rate keeps its bits.
  const std::uint8_t* slow = slow_.empty() ? nullptr : slow_.data();
  const Real weight[2] = {1.0, slowNow_};
  const Index nE = f_.nElems();
  edge_.assign(static_cast<std::size_t>(chunkCount(nE, kElemChunk)), Vec3::Zero());
  const SpringSums sums = chunkedSum(nE, kElemChunk, threads(), SpringSums(), [&](Index c0, Index c1) {
    SpringSums s;
    Index e = c0;
    while (e < c1) {  // the yarns this chunk of CPs runs through
      const Yarn& y = f_.yarns[f_.elemYarn[e]];
      const bool tensionOnly = f_.materials[y.material].tensionOnly;
      const Index end = std::min(c1, y.firstElem + y.nElems);
      if (e == y.firstElem) F[y.firstNode].setZero();
      const bool inherited = e != y.firstElem;  // the chunk before assigned this CP's first node
      for (const Index e0 = e; e < end; ++e) {
        const Index a = y.firstNode + (e - y.firstElem);
        const Vec3 d = x[a + 1] - x[a];
        const Real l = d.norm();
        const Real il = 1.0 / l;  // one division, not three
        const Vec3 n = d * il;
        const Real ldot = n.dot(v[a + 1] - v[a]);
        const Real stretch = l - l0[e];
        Real Te = K[e] * stretch;
        Real T = Te + C[e] * ldot;
        if (tensionOnly) {
          const bool taut = stretch > 0;
          Te = taut ? Te : 0.0;
          T = taut ? std::max(T, 0.0) : 0.0;
        }
        const Real w = slow ? weight[slow[e]] : 1.0;
        s.elastic += Te * stretch;              // = K*stretch^2 where the spring acts
        s.dissipated += (w * (T - Te)) * ldot;  // a non-finite l reaches both sums, even through a clamp
        if (StoreElementState) strain[e] = stretch / l0[e], tension[e] = T;
        const Vec3 Fa = (w * T) * n;
        if (inherited && e == e0) edge_[c0 / kElemChunk] = Fa;
        else F[a] += Fa;
        F[a + 1] = -Fa;
      }
    }
    return s;
  });
  for (Index k = 1; k < static_cast<Index>(edge_.size()); ++k) {
    const Index e = k * kElemChunk;
    if (e != f_.yarns[f_.elemYarn[e]].firstElem) F[f_.elem0[e]] += edge_[k];
  }
  const Real elastic = sums.elastic, dissipated = sums.dissipated;
  if (!std::isfinite(elastic + dissipated)) failNonFinite();
  books_.elastic = 0.5 * elastic + (bendingOn_ ? bendingForces() : 0.0);
  books_.damped += dissipated * dt;  // dashpot power (T-Te)*ldot = c*ldot^2 >= 0 leaves the motion
}

// Point forces, support reactions and the work of the loads over the step just made: point forces
// and body force on the drift, supports by the trapezoidal rule on their reactions (R = -f - m g at
// constant prescribed velocity).
void ChainDynamics::finishLoads(Real dt) {
  Vec3* F = f_.force.data();
  const Vec3* v = f_.vel.data();
  for (std::size_t k = 0; k < loads_.forceNodes.size(); ++k) F[loads_.forceNodes[k]] += loads_.forceValues[k];
  Real work = 0;
  const Vec3 g = loads_.bodyAcceleration;
  for (std::size_t k = 0; k < loads_.forceNodes.size(); ++k) {
    const Index i = loads_.forceNodes[k];
    if (f_.invMass[i] > 0) work += loads_.forceValues[k].dot(v[i]) * dt;
  }
  for (std::size_t k = 0; k < loads_.kinematicNodes.size(); ++k) {
    const Index i = loads_.kinematicNodes[k];
    const Vec3 R = -F[i] - f_.mass[i] * g;
    work += 0.5 * (R + loads_.reaction[k]).dot(v[i]) * dt;
    loads_.reaction[k] = R;
  }
  books_.work += work;
}

void ChainDynamics::computeForces(Real dt) {
  slowNow_ = rate_;  // forces at rest are those of a slow step's end
  springForces<true>(dt);
  finishLoads(dt);
}

void ChainDynamics::step(Real dt, StepHook* hook, bool outerEnd) {
  if (!(std::isfinite(dt) && dt > 0)) throw ParameterError("dt", fmt(dt), "(0, dt_crit] s");
  if (!started_) start();
  slowNow_ = outerEnd ? Real(rate_) : Real(0);
  const Real ramp = loads_.velocityRamp > 0 ? std::min(Real(1), (time_ + 0.5 * dt) / loads_.velocityRamp) : 1.0;
  for (std::size_t k = 0; k < loads_.kinematicNodes.size(); ++k)
    f_.vel[loads_.kinematicNodes[k]] = ramp * loads_.kinematicVelocity[k];
  Vec3 p;
  const bool gravity = loads_.bodyAcceleration.squaredNorm() > 0;
  Real ke;
  if (!hook) {
    ke = gravity ? kickDrift<true, true>(dt, p) : kickDrift<false, true>(dt, p);
  } else {
    ke = gravity ? kickDrift<true, false>(dt, p) : kickDrift<false, false>(dt, p);
    if (std::isfinite(ke)) bookContact(hook->beforeDrift(f_, dt));
    books_.spring = hook->springEnergy();
    // Springs already loaded at the hook's first step (a settled weave's locked overlaps under penalty)
    // hold energy the run starts with: it is initial energy, not an error.
    if (!springSeen_) books_.initial += books_.spring, springSeen_ = true;
    gravity ? drift<true>(dt, p) : drift<false>(dt, p);
    if (std::isfinite(ke)) bookContact(hook->afterDrift(f_, dt));
    // What the bodies gave is work on the fabric, not contact dissipation: move it across.
    const Real pe = hook->takeProjectionEnergy();
    books_.projection -= pe, books_.contactInput += std::max(Real(0), pe);
    const Real bw = hook->takeBodyWork();
    books_.work += bw, books_.bodyWork += bw, books_.contact += bw;
    // Friction's share of the contact take gets its own book (it is 0 without friction: contact keeps its bits).
    if (const Real fw = hook->takeFrictionWork(); fw != 0) books_.friction += fw, books_.contact -= fw;
  }
  if (!std::isfinite(ke)) failNonFinite();
  books_.kinetic = ke;
  if (gravity) books_.work += loads_.bodyAcceleration.dot(p) * dt;
  if (breakage_.enabled()) {
    const Real damped = books_.damped;
    springForces<true>(dt);  // strains at x_{n+1} for the breakage filter
    const long before = breakage_.brokenElements();
    const Real released = breakage_.apply(f_, dt, step_ + 1, time_ + dt);
    if (breakage_.brokenElements() > before) {  // forces and books without the broken elements
      books_.released += released;
      books_.damped = damped;
      springForces<true>(dt);
    }
  } else {
    springForces<false>(dt);
  }
  finishLoads(dt);
  ++step_;
  time_ += dt;
  dtPrev_ = dt;
  // Below dt_crit velocity Verlet keeps a linear chain's energy under invariant/(1 - (dt/dt_crit)^2),
  // which reaches 50x at 0.99 dt_crit: a budget without that factor stops stable runs.
  const Real s = dt / dtCrit_;
  const Real stableRange = s < 1 ? 1 / (1 - s * s) : 1.0;
  // |initial|: the half-drift term of penalty springs (StepHook::springEnergy) can leave it a rounding
  // below 0, and a negative budget stops a fabric at rest.
  const Real budget =
      limits.blowupFactor * stableRange * (std::abs(books_.initial) + std::abs(books_.work) + books_.contactInput) +
      0.5 * mass_ * limits.restSpeed * limits.restSpeed;
  if (books_.total() > budget) {
    Index worst = 0;
    Real worstKe = -1;
    for (Index i = 0; i < f_.nNodes(); ++i) {
      const Real k = f_.mass[i] * f_.vel[i].squaredNorm();
      if (k > worstKe) worstKe = k, worst = i;
    }
    throw InstabilityError(step_, worst, -1,
                           "energy blow-up: kinetic+elastic+damped+contact+spring+projection = " +
                               fmt(books_.total()) + " J exceeds " +
                               fmt(limits.blowupFactor) + " x (|initial| + |work| + contact input) / (1 - (dt/dt_crit)^2) + floor = " + fmt(budget) +
                               " J (time step too large, or a load out of bounds)");
  }
  // Only where a step of every rate ends (outerEnd), once per checkpointInterval chain steps: the
  // state there is whole (forces and the slow half kick owed; the collision stage's pass).
  if (limits.checkpointInterval > 0 && outerEnd && step_ % limits.checkpointInterval < chainSteps_) checkpoint();
}

void ChainDynamics::bookContact(Real added) {
  books_.contact -= added;
  books_.contactInput += std::max(Real(0), added);
}

void ChainDynamics::failNonFinite() {
  for (Index i = 0; i < f_.nNodes(); ++i) {
    if (!f_.pos[i].allFinite()) throw InstabilityError(step_ + 1, i, -1, "non-finite position");
    if (!f_.vel[i].allFinite()) throw InstabilityError(step_ + 1, i, -1, "non-finite velocity");
  }
  for (Index e = 0; e < f_.nElems(); ++e) {
    const Index a = f_.elem0[e];
    const Real l = (f_.pos[a + 1] - f_.pos[a]).norm();
    if (!(l > 0)) throw InstabilityError(step_ + 1, a, e, "element collapsed to zero length");
    const Vec3 dv = f_.vel[a + 1] - f_.vel[a];
    if (!std::isfinite(f_.stiffness[e] * l + f_.damping[e] * dv.norm()))
      throw InstabilityError(step_ + 1, a, e, "non-finite element force");
  }
  throw InstabilityError(step_ + 1, -1, -1, "non-finite energy");
}

EnergyBooks ChainDynamics::energy() const {
  EnergyBooks b = books_;
  if (!started_) {  // nothing computed yet: evaluate the state as it stands
    ChainDynamics probe(*this);
    probe.start();
    return probe.books_;
  }
  Real ke = 0;
  for (Index i = 0; i < f_.nNodes(); ++i) ke += 0.5 * f_.mass[i] * syncVelocity(i).squaredNorm();
  b.kinetic = ke;
  return b;
}

void ChainDynamics::checkpoint() {
  goodPos_ = f_.pos;
  goodVel_ = f_.vel;
  goodFlat_ = f_.secFlat;
  goodDir_ = f_.secDir;
  // Broken elements always (a loaded state may hold some with breakage off), and the books and the
  // breakage state, so that the last good state is a whole state (save_state(last_good=True)).
  goodAlive_ = f_.alive, goodStiffness_ = f_.stiffness, goodDamping_ = f_.damping;
  goodBooks_ = books_;
  goodSpringSeen_ = springSeen_;
  goodBreak_ = breakage_.state();
  goodStep_ = step_;
  goodTime_ = time_;
  goodDtPrev_ = dtPrev_;
}

void ChainDynamics::setClock(long step, Real time, Real lastDt) {
  require(step >= 0, "step", step, "[0, inf)");
  require(std::isfinite(time), "time", time, "finite [s]");
  require(std::isfinite(lastDt) && lastDt >= 0, "last_dt", lastDt, "[0, inf) s");
  step_ = step, time_ = time, dtPrev_ = lastDt;
}

void ChainDynamics::restoreLastGood() {
  if (goodPos_.size() != f_.pos.size()) return;
  f_.pos = goodPos_;
  f_.vel = goodVel_;
  f_.secFlat = goodFlat_;
  f_.secDir = goodDir_;
  if (goodAlive_.size() == f_.alive.size())
    f_.alive = goodAlive_, f_.stiffness = goodStiffness_, f_.damping = goodDamping_;
  step_ = goodStep_;
  time_ = goodTime_;
  dtPrev_ = goodDtPrev_;
  breakage_.restore(f_, goodBreak_);
  const EnergyBooks books = goodBooks_;
  const bool seen = goodSpringSeen_;
  refreshForces();
  books_ = books, springSeen_ = seen;  // the books of that state, not the ones of the failed steps
}

void ChainDynamics::restore(long step, Real time, Real lastDt, const EnergyBooks& books, bool booksStarted,
                            bool springSeen, const BreakageState& breakage) {
  const BreakageParams keepBreakage = breakage_.params();
  breakage_.restore(f_, breakage);
  step_ = step, time_ = time, dtPrev_ = lastDt;
  // The forces of the loaded positions and velocities: the same computation the saving run made at
  // the end of its step, so the same bits; the books come from the file, not from this evaluation.
  computeForces(0.0);
  // A state saved without breakage (a pretensioned weave) keeps this engine's breakage settings,
  // restarted from the loaded strains as configureBreakage would.
  if (breakage.strength.empty() && !breakage.params.enabled && keepBreakage.enabled) breakage_.configure(f_, keepBreakage);
  if (booksStarted) {
    books_ = books, springSeen_ = springSeen, started_ = true;
  } else {
    books_ = EnergyBooks(), springSeen_ = false, started_ = false;  // computed at the first step
  }
  checkpoint();
}

}  // namespace woven
