// The collision stage's sections: what flattening can still take along a contact (the rows' room,
// the capacity), the flattening passes of the contacts' sections, and the section springs' rest
// shape and forces (ContactParams::flattening; paper Section 3, the MCD).
#include "engine/CollisionStage.hpp"
#include "bound/CPBound.hpp"
#include "core/Parallel.hpp"
#include "engine/StageUtil.hpp"
#include "law/SectionFlattening.hpp"
#include <algorithm>
#include <cmath>

namespace woven {

using namespace stage;  // engine/StageUtil.hpp

// What flattening can still take along a contact's normal (both CPs) [m]: the impulse rows' room
// beyond the gap, and the overlap the position projection leaves to the next flattening passes.
std::function<Real(const CPContact&)> CollisionStage::capacityOf(const Fabric& f) const {
  return [this, &f](const CPContact& c) {
    if (params_.flattening == Flattening::None || (lockedCP(f, c.cpA, params_.mcd) && lockedCP(f, c.cpB, params_.mcd)))
      return Real(0);
    // Sections the measure memory holds (capMeasure) are not counted on to flatten: they give only
    // past what the cap holds, and that grows as the pieces move within the step (a CP end sliding
    // over a yarn at 1000 m/s: 16 um in one step, and 14 um of overlap the projection had left to
    // a flattening that could not take it).
    if (c.hHeld > 0) return Real(0);
    return capacityOne(f, c, false) + capacityOne(f, c, true);
  };
}

// One side's flattening capacity along the contact: the paper's extent of the CP (model Paper), or
// the support at the contact point (model Gap; B's side seen along -n).
Real CollisionStage::capacityOne(const Fabric& f, const CPContact& c, bool sideB, const std::vector<Real>* flat) const {
  const Index e = sideB ? c.cpB : c.cpA;
  if (c.kind == ContactKind::Paper) return flatteningCapacity(f, tangent_, e, c.normal, params_, flat);
  return flatteningCapacityAt(f, tangent_, e, sideB ? c.sB : c.sA, sideB ? Vec3(-c.hDir) : c.hDir,
                              measuresThickness(f, c), params_, flat);
}

// A gap contact whose measure is mostly the half-thickness (a persistent crossing; pieces crossing
// at more than 32.5 degrees, half way through the blend of GapFunction's thicknessWeight): it
// flattens b itself.
bool CollisionStage::measuresThickness(const Fabric& f, const CPContact& c) const {
  return c.kind == ContactKind::Crossing || (c.kind == ContactKind::Cross && crossesSteeply(f, c));
}
bool CollisionStage::crossesSteeply(const Fabric& f, const CPContact& c) const {
  if (f.elemYarn[c.cpA] == f.elemYarn[c.cpB]) return true;  // a fold: face to face (GapFunction)
  const Vec3 tA = (f.pos[f.elem0[c.cpA] + 1] - f.pos[f.elem0[c.cpA]]).normalized();
  const Vec3 tB = (f.pos[f.elem0[c.cpB] + 1] - f.pos[f.elem0[c.cpB]]).normalized();
  return std::abs(tA.dot(tB)) < 0.84339144581288572;  // cos 32.5 degrees
}

// Paper Sec. 5.1 steps 1-3: take up each overlap by flattening the sections of both CPs (half each,
// the rest by the other when one is locked), re-test the contacts whose CPs changed, repeat.
int CollisionStage::flatten(Fabric& f, int maxPasses, Real bodyDt) {
  const Real tiny = 1e-15;  // [m]
  int passes = 0;
  for (; passes < maxPasses; ++passes) {
    flatBefore_ = f.secFlat;
    dirSum_.resize(f.pos.size(), Vec3::Zero());
    dirty_.assign(f.elem0.size(), 0);
    bool any = false;
    // The capacities are measured for every contact at once (threads), then the contacts flatten in
    // order. A capacity reads the snapshot flatBefore_, except that flatteningDirection lets a node that
    // is still circular (secFlat 0) turn freely: a node circular at the pass start and flattened by an
    // earlier contact of this pass changes that, so those CPs are measured again in the loop (the
    // serial order's result, the same bits at any thread count).
    // The contacts that can flatten (overlapping, not both locked at the pass start: capacity 0
    // leaves them to the impulses) listed by fixed chunks, in order.
    const Index nc = static_cast<Index>(contacts_.size());
    capacity_.resize(2 * contacts_.size());
    constexpr Index kChunk = 4096;
    flattenChunks_.resize(chunkCount(nc, kChunk));
    parallelFor(static_cast<Index>(flattenChunks_.size()), 2, threads(), [&](Index t) {
      std::vector<Index>& mine = flattenChunks_[t];
      mine.clear();
      for (Index k = t * kChunk, end = std::min(nc, k + kChunk); k < end; ++k) {
        const CPContact& c = contacts_[k];
        if (c.time > 0 || !(c.gap < -tiny)) continue;
        if (lockedCP(f, c.cpA, params_.mcd) && lockedCP(f, c.cpB, params_.mcd)) continue;
        capacity_[2 * k] = capacityOne(f, c, false, &flatBefore_);
        capacity_[2 * k + 1] = capacityOne(f, c, true, &flatBefore_);
        mine.push_back(k);
      }
    });
    joinChunks(flattenChunks_, flattenList_, threads());
    for (const Index k : flattenList_) {
      const CPContact& c = contacts_[k];
      // locked since the pass started, by an earlier contact of this loop
      if (lockedCP(f, c.cpA, params_.mcd) && lockedCP(f, c.cpB, params_.mcd)) continue;  // capacity 0: left to the impulses
      const Real need = c.hHeld - c.gap;  // the capped measure gives only past what the cap holds
      const auto turnedThisPass = [&](Index e) {
        const Index i = f.elem0[e];
        return (flatBefore_[i] == 0 && f.secFlat[i] != 0) || (flatBefore_[i + 1] == 0 && f.secFlat[i + 1] != 0);
      };
      const Real capA = turnedThisPass(c.cpA) ? capacityOne(f, c, false, &flatBefore_) : capacity_[2 * k];
      const Real capB = turnedThisPass(c.cpB) ? capacityOne(f, c, true, &flatBefore_) : capacity_[2 * k + 1];
      if (capA + capB <= tiny) continue;  // locked: left to the impulses
      Real dA = std::min(capA, 0.5 * need);
      const Real dB = std::min(capB, need - dA);
      dA = std::min(capA, need - dB);
      if (c.kind == ContactKind::Paper) {
        flattenCP(f, tangent_, c.cpA, c.normal, dA, params_, flatBefore_, dirSum_);
        flattenCP(f, tangent_, c.cpB, c.normal, dB, params_, flatBefore_, dirSum_);
      } else {  // the gap model measures at the contact point: flatten there
        const bool thickness = measuresThickness(f, c);
        flattenAt(f, tangent_, c.cpA, c.sA, c.hDir, thickness, dA, params_, flatBefore_, dirSum_);
        flattenAt(f, tangent_, c.cpB, c.sB, Vec3(-c.hDir), thickness, dB, params_, flatBefore_, dirSum_);
      }
      for (Index e : {c.cpA, c.cpB})
        for (Index q = std::max(e - 1, 0); q <= std::min(e + 1, f.nElems() - 1); ++q)
          if (f.elemYarn[q] == f.elemYarn[e]) dirty_[q] = 1;
      ++stats.flattened;
      any = true;
    }
    // The body contacts (model Gap, within a step): the paper's response (Sec. 5.1 steps 1-3) holds
    // for any two colliding OBBs, the projectile's among them. A body flattens nothing; the CP's
    // sections at the contact take up the overlap (and what the measure memory holds back) along the
    // normal, up to the MCD. Without it, at 4 CPs per span a sphere reaching a node between two
    // crossings, still round (2.4 times the flattened half-thickness), sat 15 um inside it.
    bool bodyFlattened = false;
    if (bodyDt >= 0 && params_.model == ContactModel::Gap && params_.flattening == Flattening::Geometric)
      for (const BodyContact& c : bodyContacts_) {
        if (!(c.gap < -tiny) || lockedCP(f, c.cp, params_.mcd)) continue;
        const Real cap = flatteningCapacityAt(f, tangent_, c.cp, c.s, c.normal, false, params_, &flatBefore_);
        if (cap <= tiny) continue;
        flattenAt(f, tangent_, c.cp, c.s, c.normal, false, c.held - c.gap, params_, flatBefore_, dirSum_);
        for (Index q = std::max(c.cp - 1, 0); q <= std::min(c.cp + 1, f.nElems() - 1); ++q)
          if (f.elemYarn[q] == f.elemYarn[c.cp]) dirty_[q] = 1;
        ++stats.flattened;
        any = bodyFlattened = true;
      }
    if (!any) break;
    turnSections(f, tangent_, flatBefore_, dirSum_);
    if (sectionStamp_.size() != f.elem0.size()) sectionStamp_.assign(f.elem0.size(), 0);
    parallelFor(f.nElems(), kParallelGrain, threads(), [&](Index e) {
      if (dirty_[e]) {
        bounds_[e] = cpBound(f, tangent_, e, params_.rule, params_.margin);
        sectionStamp_[e] = cacheClock_;  // the cached contacts of this CP no longer hold
      }
    });
    parallelFor(nc, 256, threads(), [&](Index k) {  // each contact on its own
      CPContact& c = contacts_[k];
      if (c.time > 0 || !(dirty_[c.cpA] || dirty_[c.cpB])) return;
      if (c.kind != ContactKind::Paper) return remeasure(f, c, params_.rule, true, &tangent_);  // same points, new sections
      CPContact again;
      if (cpContactStatic(f, bounds_, c.cpA, c.cpB, params_.margin, params_.rule, again)) c = again;
      else c.gap = 2 * params_.margin;  // apart now: at least this far
    });
    if (bodyFlattened) measureBodies(f, bodyDt);  // the flattened sections, the same memory
  }
  return passes;
}

// Flattening Springs: the sections are elastic (paper Eq. 7: a spring between the axis node and the
// ellipse node). Each step they start from their shape at the first step (a built weave's settled
// sections) and flatten again, geometrically up to the MCD, as far as this step's overlaps ask;
// the deformation beyond the rest shape then pushes back (addSectionSprings). So the section's
// flattening is a function of the positions and its spring energy is a potential.
void CollisionStage::restoreSections(Fabric& f) {
  if (restFlat_.size() != f.secFlat.size()) restFlat_ = f.secFlat, restDir_ = f.secDir;
  f.secFlat = restFlat_;
  f.secDir = restDir_;
}

// The paper's Eq. 7, F_i = k_i (u_i^2 - u_i^1), is a spring between node i's axis position u^1 and
// its ellipse node u^2; here |u^2 - u^1| - r0 is the flattening r0 eps (beyond the rest shape) and
// k_i = k_s, so node k pushes back with k_s r0 eps_k along its flattening direction. The force
// reaches the yarns through the contacts pressing the node: node k's force is shared among its
// contacts in touch in proportion to its weight |w| in each (the impulse weights), and a contact
// gets half the sum over its four nodes (the A side and the B side carry the same force, springs in
// series). One contact in the middle of two CPs overlapping by delta: each node flattens by
// delta/2, the contact force is 2 x k_s delta/2 = k_s delta, the derivative of the energy
// 4 x 1/2 k_s (delta/2)^2. The flattening cosine (dir.n, 1 for a square crossing) is neglected.
// Returns the energy 1/2 k_s (r0 eps)^2 of the flattened sections [J].
Real CollisionStage::addSectionSprings(const Fabric& f) {
  const Real ks = params_.sectionStiffness, touch = 2 * params_.margin + 1e-12;
  nodeWeight_.assign(f.secFlat.size(), 0);
  auto nodesOf = [&](const CPContact& c, Index* node, Real* w) {
    node[0] = f.elem0[c.cpA], node[1] = node[0] + 1, node[2] = f.elem0[c.cpB], node[3] = node[2] + 1;
    w[0] = 1 - c.sA, w[1] = c.sA, w[2] = 1 - c.sB, w[3] = c.sB;
  };
  Index node[4];
  Real w[4];
  for (const CPContact& c : contacts_) {
    if (c.time > 0 || c.gap > touch) continue;
    nodesOf(c, node, w);
    for (int q = 0; q < 4; ++q) nodeWeight_[node[q]] += w[q];
  }
  for (const CPContact& c : contacts_) {
    if (c.time > 0 || c.gap > touch) continue;
    nodesOf(c, node, w);
    Real F = 0;
    for (int q = 0; q < 4; ++q) {
      const Index k = node[q];
      const Real d = f.secRadius[k] * (f.secFlat[k] - restFlat_[k]);
      if (d > 0 && nodeWeight_[k] > 0) F += 0.5 * ks * d * w[q] / nodeWeight_[k];
    }
    if (F > 0) forces_.addYarn(f, c, F, ks, 0);
  }
  Real energy = 0;
  for (std::size_t k = 0; k < restFlat_.size(); ++k) {
    const Real d = f.secRadius[k] * (f.secFlat[k] - restFlat_[k]);
    if (d > 0) energy += 0.5 * ks * d * d;
  }
  return energy;
}

}  // namespace woven
