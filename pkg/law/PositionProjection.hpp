// Position projection after the drift (contact model `gap`; docs/collisions.md): the nodes (and
// bodies) of contacts that end the step overlapping are moved apart along the gradient of the same
// gap function the impulse rows are made of (geom/GapFunction.hpp), so nothing ratchets: what the
// rows let through, the projection takes back on the same measure. Nonlinear Gauss-Seidel on
// positions (Box2D's NGS; Catto, "Modeling and Solving Constraints"): per sweep and contact,
// g is measured again at the current positions and, where g + allowance < -slop,
//     x_k += (w_k / m_k) dl grad_k,   dl = -(g + allowance + kRebound slop) / sum_k |grad_k|^2 / m_k,
// scaled down where a node would move more than maxMove (or kProjectionTravel maxMove in all),
// with a body's share dl n / M and its turn I^-1 (r x n) dl. The allowance is what flattening can
// still take along the normal (the next step's flattening passes absorb that part). Velocities are
// not changed. The energy the moves put in is returned for the books (EnergyBooks::projection):
// the spring energy of the CPs whose nodes moved, and the change of the step's kinetic energy that
// their changed forces make (dF . dx / 2 over the drift dx = dt v). The contacts are swept colour by
// colour (law/RowColouring: a colour's contacts share no node, so they move at once on the threads)
// or block by block (law/RowBlocks: the blocks at once, then the seam), the body contacts last, in
// order: the same bits on any thread count.
//
// The check (`checkDepth` >= 0, CollisionStage::beforeDrift): the same projection once more at the
// step's start, after the flattening passes, with no allowance (flattening has had its turn), seeded
// by the contacts still deeper than checkDepth. What the projection after the last drift left to
// the flattening and the flattening did not take (its measure changed under it: a piece turning
// from crossing to side by side, a closest point moving onto a rounder section) is taken out before
// the rows act on it. Its moves count against each node's travel in the projection after this
// step's drift (kCheckTravel).
#pragma once
#include "fabric/Fabric.hpp"
#include "geom/BodyContact.hpp"
#include "geom/CPContact.hpp"
#include "geom/GapFunction.hpp"
#include "law/ContactParams.hpp"
#include "law/RowBlocks.hpp"
#include "law/RowColouring.hpp"
#include <functional>
#include <vector>

namespace woven {

struct ProjectionReport {
  int sweeps = 0;         ///< sweeps made
  std::int32_t padding_ = 0;  // explicit: saved raw with the collision statistics (CollisionStats)
  long pushed = 0;        ///< contact moves made (over all sweeps)
  Real energy = 0;        ///< energy the moves put in [J] (< 0: taken out): springs and the step's kinetic energy
  Real overlapLeft = 0;   ///< largest overlap beyond allowance + slop met in the last sweep made [m] (0: none)
};

/// A contact deeper than the slop is moved to (1 - kRebound) slop deep (Box2D moves it to the slop
/// itself): the rest of the slop is hysteresis. A contact left at the slop is pushed again by
/// the least further overlap, and its neighbours' pushes move it: measured on the default impact,
/// a persistent crossing's push of 0.1 um moved its neighbours' nodes by 1-2 % of it, 1 100
/// crossings a step were pushed by about 0.1 um in cascades through the ply, and every sweep ran.
constexpr Real kRebound = 0.5;
/// A node is moved at most this many times maxMove in one projection (and maxMove by one contact).
constexpr Real kProjectionTravel = 3;
/// A check moves a node at most this many times maxMove; the projection after the same step's drift
/// then moves it only as far as the check left of kProjectionTravel maxMove. Beyond the listing's
/// reach (kProjectionTravel maxMove) only in a step whose check met an overlap that deep: a pair
/// turning side by side whose new end point, at a rounder section the crossing had not measured,
/// sat 34 um inside a broken piece lying over a clamped node (6 mm cube at 600 m/s, 4 CPs): 37.5 um
/// of the piece's node's travel. A neighbour such a move reaches unlisted is measured at the next
/// step, as a new contact, and checked there.
constexpr Real kCheckTravel = 6;

class PositionProjection {
 public:
  /// What flattening can still take along a contact's normal (both CPs) [m].
  using Allowance = std::function<Real(const CPContact&)>;

  /// Projects the contacts of the step (measured again here; their normals and weights are updated)
  /// with `sweeps` sweeps and the slop [m]; no contact moves a node more than maxMove [m], and no
  /// node moves more than kProjectionTravel maxMove in all (Box2D's maxLinearCorrection: a deep
  /// overlap, say a whipping broken end's, is taken out over a few steps instead of throwing the
  /// nodes into neighbours no contact was listed for; measured on a perforated 8 mm ply: 3 x halved
  /// the mean overlap of 1 x, 10 x injected 5 times the energy).
  /// checkDepth >= 0: the check before the drift (see above): the first sweep takes only the
  /// contacts whose gap (as last measured) is below -checkDepth, the allowance is not asked, and the
  /// energy is booked for moves made before the drift.
  /// `travelled` (may be null): per node, how far it can have moved since the contacts' gaps were
  /// measured [m]. The first sweep then skips a contact whose gap, less what its nodes' travel can
  /// close (twice the farthest of its stencil's nodes), stays above -slop:
  /// measured, it would not be pushed (the same moves, without measuring most of a ply at rest).
  void project(Fabric& f, std::vector<CPContact>& contacts, std::vector<BodyContact>& bodyContacts,
               std::vector<RigidBody>& bodies, const Allowance& allowance, int sweeps, Real slop, Real maxMove,
               SectionRule rule, Real dt, ProjectionReport& report, SweepOrder order = SweepOrder::Coloured,
               Real checkDepth = -1, const Real* travelled = nullptr);

 private:
  /// Contacts of a colour below which it is projected on one thread.
  static constexpr Index kContactGrain = 256;
  Real bookedEnergy(Fabric& f, Real dt);  // the energy the moves put in [J] (see project)
  std::vector<Real> allowance_;       // per contact, measured once per call (NaN: not yet)
  struct Slot {
    Index q, cpA, cpB;                // the contact and its CPs
    int n;                            // its stencil's nodes (GapFunction's contactStencil), which
    Index node[kMaxStencil];          // a sweep checks for moves before it reads the contact
  };
  std::vector<Slot> slots_;           // the contacts in colour order
  // The sequential order's later sweeps: each node's slots (CSR, built when a second sweep comes),
  // the nodes the sweep before moved, and the slots to take.
  std::vector<Index> nodeStart_, nodeSlots_, movedBeforeList_, work_;
  Index nodeSlotsFor_ = -1;
  std::vector<Real> outcome_;         // per slot: the overlap its contact's move in this sweep took out [m] (0: none)
  RowColouring colouring_;            // of the contacts, by their four nodes
  RowBlocks blocking_;                // of the contacts, by their four nodes (SweepOrder::Blocked)
  std::vector<Index> elems_;          // the CPs with a moved node, in order
  std::vector<std::uint8_t> movedBefore_, movedNow_, movedAny_;  // per node: moved in the sweep before / in this one / at all
  std::vector<Real> travel_;                          // per node: distance moved in this call (and the check before it) [m]
  bool checked_ = false;                              // a check ran since the last projection: travel_ carries its moves
  Vec3Array origin_;                                  // per moved node: its position before the projection
  Vec3Array forceBefore_;                             // per element of elems_: its spring force before the moves
};

}  // namespace woven
