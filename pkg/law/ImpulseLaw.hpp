// Second half of the paper's response (Sec. 5.1): impulses where flattening cannot take up the
// approach. For a contact with normal n (A towards B), point weights s_A, s_B along the two CPs, the
// relative normal velocity of the contact points is (Eq. 4)
//     vn = (v_B(s_B) - v_A(s_A)) . n,   v_X(s) = (1 - s) v_X0 + s v_X1,
// approaching when vn < -tolerance, resting within +-tolerance, separating above. An impulse J n
// on B and -J n on A changes vn by J / m_eff with 1/m_eff = sum over the 4 nodes of w^2/m (the Eq. 5
// masses seen through the barycentric weights), so Eq. 5 reads J = -(1 + e) vn m_eff.
//
// A contact gets an impulse row when its approach within the step exceeds what flattening can still
// absorb, room = gap + capacity (0 for a contact still overlapping after the flattening passes):
// vn < -room/dt - tolerance. Two passes, as in Box2D v3:
//  1. before the drift, target vn' = -room/dt: the pair uses up exactly its room by the end of the
//     step (a contact found by the moving test closes its gap: no tunnelling, no early stop; a
//     locked contact in touch stops approaching: Eq. 5 with e = 0);
//  2. after the drift (restitute), rows that pushed and approached faster than the tolerance get
//     vn' >= -e vn0: with the pair now in touch, Eq. 5 with the approach speed vn0 it had.
// A contact of a CP with a rigid body (geom/BodyContact) is a row whose B side is the body: its
// velocity at the point is v + w x r, and 1/m_eff gains 1/M + (r x n) . I^-1 (r x n), so the body's
// velocity and angular velocity change with its mass and inertia (J n on the body, -J n on the CP:
// momentum is exchanged exactly). Its room is the gap alone: a body does not flatten the sections.
// Simultaneous rows are solved by projected Gauss-Seidel on accumulated impulses (J >= 0, and the
// Coulomb friction impulse within mu J; mu = ContactParams::friction between yarns, bodyFriction on
// body rows) until no row misses its target by more than the tolerance or maxIterations is reached;
// the residual and unresolved rows are reported, never hidden. The sweeps are coloured
// (law/RowColouring): rows that share no node are solved at once on the threads, colour after
// colour, the rows on a rigid body last in row order; the colouring follows the row list alone, so
// every thread count gives the same bits.
//
// Friction's share of the energy (EnergyBooks::friction). The solve applies to each row r its
// accumulated impulse J_r = lambda_r n_r + lambdaT_r; the node velocities change by dv = sum_r w J_r / m,
// linear in the J_r, so the integer-step kinetic energy the books keep (energyChange) changes by
// exactly sum_i m_i dv_i . (v_i + v'_i)/2 (at the synchronised velocities) = sum_r J_r . ((u_r + u'_r)/2 - k_r),
// u_r and u'_r the row's relative velocity before and after the whole solve, k_r = (dt/2) sum w a its
// half kick (and a body's half host kick on a body row, whose own kinetic energy the books count the
// same way). Friction's share is its tangential part, -sum_r lambdaT_r . ((u_r + u'_r)/2 - k_r), in row
// order: the final tangential impulse against the mean slip over the step; the normal impulses' book
// is the rest, and the two add up to the measured change exactly. The split is a function of the
// solve's result, not of its path. Splitting each Gauss-Seidel update's increment instead
// also closes, but the sweeps push and give back normal and tangential impulse many
// times a step: in the pull-out at friction 0.15 (4 N) the normal increments' shares were -22.8 and
// +20.8 mJ against a physical 0.7 mJ, and their residue, -0.5 mJ, booked the normal impulses as
// putting energy in, with friction taking more than the rows took in all (docs/pullout.md).
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

static_assert(kMaxStencil <= kMaxRowNodes, "a row holds every node of its contact's stencil");

struct ImpulseReport {
  long rows = 0;            ///< contacts that received impulses
  int iterations = 0;       ///< Gauss-Seidel sweeps made
  std::int32_t padding_ = 0;  // explicit: saved raw with the collision statistics (CollisionStats)
  Real residual = 0;        ///< largest miss of a row's target after the last sweep [m/s]
  long unresolved = 0;      ///< rows still missing their target by more than the solve's tolerance (ContactParams::solverTolerance)
  long skipped = 0;         ///< row updates the sweeps skipped (nothing had changed them: the active set)
  long unresolvedBand = 0;  ///< rows missing their target by more than Eq. 4's band (ContactParams::tolerance)
  Real energyChange = 0;    ///< change of the step's kinetic energy (v_n) the impulses make [J]
  /// Work the rigid bodies did on the fabric [J]: minus their kinetic energy change (dynamic
  /// bodies), the impulse on the fabric times the body's velocity at the point (kinematic ones).
  Real bodyWork = 0;
  /// Of the energy the impulses took (-energyChange + bodyWork), what their tangential parts took [J]
  /// (see above; 0 without friction).
  Real frictionWork = 0;
};

class ImpulseLaw {
 public:
  /// Rows of a colour below which it is solved on one thread (a parallel region costs a few us).
  static constexpr Index kRowGrain = 256;
  /// The sweeps' active set (the serial tail's rows; the blocks' in the blocked order): an update
  /// that changes its row's velocity by more than this fraction of the solve's tolerance has the
  /// rows of its nodes updated again.
  static constexpr Real kWake = 1;

  /// What flattening can still take along a contact's normal (both CPs) [m]; asked only for contacts
  /// that approach faster than their gap alone allows.
  using Capacity = std::function<Real(const CPContact&)>;

  /// Applies the impulses to Fabric::vel (and to the bodies' vel and angVel); dt [s] the step (its
  /// half-kick: the energy books), horizon [s] the drift until the next pass, over which the rows
  /// let a contact close by its room (dt itself, or the contact step of spring substeps:
  /// FabricEngine::setSubsteps); 0: dt. only: per contact 1 if it may get a row (null: every one).
  void resolve(Fabric& f, const std::vector<CPContact>& contacts, const Capacity& capacity, Real dt,
               const ContactParams& p, ImpulseReport& report, const std::vector<BodyContact>& bodyContacts = {},
               std::vector<RigidBody>* bodies = nullptr, Real horizon = 0, const std::uint8_t* only = nullptr);

  /// Each contact's normal impulse after the last resolve() [N s] (0: no row), for `contacts`
  /// contacts in the order resolve() had them: the persistent crossings' warm start
  /// (CPContact::warm) at the next step.
  void contactImpulses(std::size_t contacts, std::vector<Real>& out) const;

  /// Pass 2 after the drift: restitution e of the rows of the last resolve() (see above). Returns
  /// the fabric's kinetic energy change [J] (0 for e = 0) and adds the bodies' work to *bodyWork.
  Real restitute(Fabric& f, const ContactParams& p, std::vector<RigidBody>* bodies = nullptr, Real* bodyWork = nullptr);

  /// Moves the nodes of contacts still overlapping (gap < 0) apart along the normal by
  /// positionCorrection * (-gap), weighted by w/m as an impulse would, each node only across its own
  /// CP (the part along the CP is dropped: it would load the stiff axial spring at once).
  /// Only contacts whose gap was measured across both sections: a normal along a yarn (end-on
  /// contacts, kinked or self-touching yarns) would stretch the stiff axial springs, so those
  /// overlaps are only kept from growing by the impulses.
  /// Returns the spring energy this puts in [J] (exact, over the CPs it stretches), for the books.
  static Real correctPositions(Fabric& f, const std::vector<CPContact>& contacts, const ContactParams& p);

 private:
  // Trivially constructible (every field set where a row is made): a contact's slot is made for each
  // contact each step, and initialising them all cost 4 % of the default impact.
  struct Row {
    Index node[kMaxStencil];
    int n;              // nodes (GapFunction's contactStencil; 2 on a body)
    int body;           // B side: a rigid body (the nodes are the CP's two), at arm r from its centre
                        // (-1: none); beside the nodes: the colouring and the blocks read both
    Real w[kMaxStencil];  // the stencil's weights (a CP pair: -(1-sA), -sA, (1-sB), sB): vn = sum w_k v_k . normal
    Vec3 normal;
    Real target, invK;  // invK = m_eff = 1 / sum w^2/m
    Real vn0;           // normal velocity before the impulses [m/s]
    Real lambda;        // accumulated normal impulse [N s]
    Vec3 lambdaT;
    // friction's energy share: the row's half kick k less half its relative velocity before the solve
    // (before the warm start), k - u/2 (after it, the share is -lambdaT . (u'/2 - this)) [m/s]
    Vec3 kick;
    Vec3 arm;
    Index contact;      // the contact it is the row of (-1: a body contact)
  };
  // What an update without friction of a row on no body reads and writes, packed (104 B against a
  // Row's 192): a sweep streams every row, and this nearly halves the memory it moves.
  struct SweepRow {
    Index node[kMaxStencil];
    Real w[kMaxStencil];
    int n;
    Vec3 normal;
    Real target, invK, lambda;
    bool body;  // a row on a body: updated as a Row (solveRow), its lambda kept there
  };
  struct BodyVelocity {  // a body's velocities while the rows are solved
    Vec3 v, w;
    Real invM;
    Mat3 invI;
    Real ke0 = 0;        // kinetic energy before the impulses [J]
    Vec3 v0 = Vec3::Zero();        // velocity before the impulses [m/s]
    Vec3 halfKick = Vec3::Zero();  // RigidBody::hostKick / 2 of a dynamic body [m/s]
    Real friction = 0;             // Coulomb coefficient with the yarns: its own, else ContactParams::bodyFriction
  };
  Vec3 rowVelocity(const Fabric& f, const Row& r) const;     // relative velocity of the contact points
  void applyRow(Fabric& f, const Row& r, const Vec3& J);      // J on B, -J on A
  void loadBodies(const std::vector<RigidBody>* bodies, Real bodyFriction);
  // writes back, returns the bodies' work (their kinetic energy at the synchronised velocity: step
  // n's before the drift, step n+1's after it)
  Real storeBodies(std::vector<RigidBody>* bodies, bool afterDrift);
  template <class RowAt>
  void colourRows(const Fabric& f, Index n, SweepOrder order, RowAt&& rowAt);  // rows_ by colour or block, start_ set
  void serialLayout(Index n);  // no colours: rows_[0, n) all in the serial tail, start_ set
  Real solveRow(Fabric& f, Row& r, const ContactParams& p, bool friction);  // returns the row's miss
  static Real solveRow(Fabric& f, SweepRow& r);  // the same update, for a row without friction or body
  int solve(Fabric& f, const ContactParams& p, bool friction);  // Gauss-Seidel sweeps in rows_'s layout, returns the count
  void keepVelocities(const Fabric& f);      // of the touched nodes, before the impulses
  // Kinetic energy of the integer step the impulses add [J]: step n's, or step n+1's after the drift.
  Real energyChange(const Fabric& f, bool afterDrift) const;
  std::vector<Row> rows_, sorted_;
  std::vector<SweepRow> packed_;  // solve: rows_ packed, while friction between yarns is off
  std::vector<Row> slots_;      // resolve: per contact its row (where hasRow_)
  std::vector<std::uint8_t> hasRow_;
  std::vector<Index> yarnRows_;  // the contacts with a row, in order
  std::vector<Row> bodyRows_;
  RowColouring colouring_;
  RowBlocks blocking_;
  // rows_[start_[c], start_[c + 1]): colour c (or block c), the serial tail from start_[kColours]
  Index start_[RowColouring::kColours + 2] = {};
  int colours_ = 0;                               // colours in use (0: every row in the tail)
  int blocks_ = 0;                                // blocks in use (SweepOrder::Blocked; then no colours)
  std::vector<Real> miss_;                        // per row: its miss in the last sweep [m/s]
  std::vector<BodyVelocity> bodyVel_;
  Vec3Array vBefore_;
  Real dt_ = 0;
  std::vector<Index> touched_;
  std::vector<std::uint8_t> marked_;
  // The active set (solve): the serial tail's rows, or the blocks' (SweepOrder::Blocked), in
  // regions (the tail, or a block each) whose bits start on a word of their own.
  struct Region {
    Index row0, row1, bit0;  // rows_[row0, row1), their bits from bit0
  };
  Region region_[RowBlocks::kBlocks] = {};
  Index bitCount_ = 0;  // bits of the sets (each region's rounded up to a word)
  // Each node's rows of the active set (CSR, as bits) and a bit per row to update.
  std::vector<Index> nodeStart_, nodeRows_, fill_;
  std::vector<Index> wordStart_, words_;  // per node its tail rows' words of the bit sets (CSR) ...
  std::vector<std::uint64_t> masks_;      // ... and each word's rows
  std::vector<std::uint64_t> dirty_, next_;  // this sweep's rows to update (after the one updated), the next sweep's
  std::vector<Index> tailBodies_;              // the tail's rows on a body, by their place in the tail
  long skipped_ = 0;  // row updates the active set skipped in the last solve
  Real solverTol_ = 0;  // the solve's tolerance on a row's miss [m/s] (resolve)
};

}  // namespace woven
