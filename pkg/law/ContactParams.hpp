// Parameters of the collision response (paper Sec. 5), all SI, validated with the allowed ranges.
#pragma once
#include "core/Types.hpp"
#include "shape/Section.hpp"
#include <cstdint>
#include <string>

namespace woven {

/// How overlaps that flattening leaves are resolved (docs/collisions.md, "Response and section models").
enum class Response : std::uint8_t {
  Impulse = 0,  ///< impulses of Eq. 5 solved by Gauss-Seidel (law/ImpulseLaw), the paper's response
  Penalty = 1   ///< a normal spring force k_p delta (+ dashpot) on every overlapping contact (law/NormalForces)
};
/// What the cross-sections do under contact (paper Sec. 5.2.2).
enum class Flattening : std::uint8_t {
  Geometric = 0,  ///< flatten up to the MCD at no force (the paper's default model)
  None = 1,       ///< sections never change during the steps (settle() still shapes a built weave)
  Springs = 2     ///< flatten as Geometric, and each flattened node section pushes back with k_s r0 eps (Eq. 7)
};
/// Which gap function the contacts are measured, solved and projected on (docs/collisions.md).
enum class ContactModel : std::uint8_t {
  /// One gap function per contact kind, each impulse row its exact gradient, and a position
  /// projection after the drift on the same functions (geom/GapFunction.hpp; the default).
  Gap = 0,
  /// The paper's (Sections 4-5): the separating-axis translation distance as the normal, the depth
  /// on the sections along it, moving SAT for first contacts, pre-drift positional correction.
  Paper = 1
};
/// Row order of the Gauss-Seidel sweeps (impulse rows and position projection; law/RowColouring,
/// law/RowBlocks).
enum class SweepOrder : std::uint8_t {
  /// Colour by colour (rows of a colour share no node, solved at once on the threads), the rows on
  /// a rigid body last: the order that lets the sweeps use the threads.
  Coloured = 0,
  /// One row after another in contact order, the body rows last: serial, the default (no two-thread
  /// gain of the coloured order measured yet, and 5-15 % slower on one thread; docs/design.md).
  Sequential = 1,
  /// Block by block (law/RowBlocks: slabs of the ply whose rows share no node, solved at once, each
  /// in contact order), then the rows across the slabs' cuts and the body rows, in order: a barrier
  /// per phase instead of one per colour. Each block's rows have the sequential order's active set;
  /// the cuts' and the tail's are updated every sweep.
  Blocked = 2
};
/// How the gap model measures where two yarns cross (docs/collisions.md, "Persistent crossings").
enum class Crossings : std::uint8_t {
  /// One persistent contact per crossing, carried from step to step on the yarns' smooth centre
  /// lines (engine/CrossingContacts); its chord pairs never reach the general pipeline (the default).
  Persistent = 0,
  /// Every CP pair measured afresh each step by the general pipeline: four chord-pair contacts per
  /// crossing at one CP per span (the model before persistent crossings).
  Chords = 1
};
/// "persistent" or "chords"; throws ParameterError("crossings") otherwise.
Crossings crossingsByName(const std::string& name);
/// "coloured", "sequential" or "blocked"; throws ParameterError("sweep_order") otherwise.
SweepOrder sweepOrderByName(const std::string& name);
/// "gap" or "paper"; throws ParameterError("contact_model") otherwise.
ContactModel contactModelByName(const std::string& name);
/// "impulse" or "penalty"; throws ParameterError("response") otherwise.
Response responseByName(const std::string& name);
/// "geometric", "none" or "springs"; throws ParameterError("flattening") otherwise.
Flattening flatteningByName(const std::string& name);

struct ContactParams {
  ContactModel model = ContactModel::Gap;
  /// Sweeps of the position projection after the drift (model Gap, response Impulse), in [0, 50];
  /// -1 (auto): 8 there (it stops early once nothing moves), 0 elsewhere. A count >= 1 with model Paper or response Penalty is refused
  /// (those keep their own overlap handling).
  int projectionSweeps = -1;
  /// Overlap the projection leaves alone [m] >= 0 (Box2D's linear slop).
  Real projectionSlop = 0.5e-6;
  /// Most one contact moves a node in a position projection [m] > 0 (Box2D's maxLinearCorrection;
  /// a node moves at most kProjectionTravel times this in all, and pairs that much closer than the
  /// step's motion allows are listed as contacts, so a move never carries a node into an unlisted
  /// neighbour). 10 um, a tenth of a KM2 yarn's thickness.
  Real projectionMaxMove = 10e-6;
  /// The check [m] (PositionProjection): contacts still deeper than this after the flattening
  /// passes are projected (no allowance) before the rows; -1: no check. In [0, 1e-3] or -1; acts
  /// where the projection does (projectionSweepCount() > 0). 2 um, 0.018 of a KM2 yarn's thickness.
  Real projectionCheck = 2e-6;
  /// The sweeps the projection makes with these parameters.
  int projectionSweepCount() const {
    if (projectionSweeps >= 0) return projectionSweeps;
    return model == ContactModel::Gap && response == Response::Impulse ? 8 : 0;
  }
  Real restitution = 0.0;     ///< e of Eq. 5 in [0, 1]; 0: "at the next time moment both nodes move together"
  Real friction = 0.0;        ///< Coulomb coefficient mu in [0, 2] between yarns (0 as in the paper)
  /// Coulomb coefficient in [0, 2] between a rigid body and the yarns (the impulse rows whose B side
  /// is a body): a steel projectile on aramid is not a yarn on a yarn.
  Real bodyFriction = 0.0;
  Real mcd = 0.6;             ///< maximum cross-sectional deformation in (0, 1) (paper: 0.5-0.7)
  SectionRule rule = SectionRule::ConstantArea;
  Real margin = 1e-6;         ///< added to every side of a CP's OBB [m] >= 0: contacts start this close
  /// Extra growth of the broad-phase boxes [m] >= 0 (a Verlet skin): the candidate pairs are kept
  /// while every CP's box (grown by its motion in the step) stays inside its box of the last broad
  /// phase; 0 runs the broad phase every step. The pairs found are the same either way.
  Real skin = 5e-6;
  Real tolerance = 1e-6;      ///< Eq. 4 resting band on normal velocity [m/s] > 0 (and the solve's least tolerance)
  /// The impulse solve's own tolerance [m] in [0, 1e-3]: the sweeps stop once no row's miss errs
  /// the drift of the step by more than this (a miss of solverTolerance / dt, and never less than
  /// `tolerance`); rows over it are the unresolved ones. 1 nm: 0.2 % of the projection's slop, so
  /// what a row misses takes hundreds of steps to reach what the projection takes out. 0: the
  /// tolerance alone (1e-6 m/s, 7e-14 m a step at the default ballistic step). The gap model only
  /// (its targets take a miss back at the next step); the paper model's solve stops at `tolerance`.
  Real solverTolerance = 1e-9;
  int maxIterations = 50;     ///< bound on the impulse iterations per step, >= 1
  int flattenPasses = 4;      ///< re-tests of flattened contacts per step (paper's "go to steps 1 and 2"), >= 1
  /// Model Paper: fraction in [0, 1] of a residual (locked) overlap removed per step by moving the nodes apart
  /// (weighted like an impulse, each node across its own CP; its spring energy is booked;
  /// docs/collisions.md). Box2D's 0.2: a whole overlap removed in one step kicks the springs.
  Real positionCorrection = 0.2;
  /// Overlap left alone by the positional correction [m] >= 0 (Box2D's linear slop): below it, the
  /// correction would only push against the contact force every step and the impulses take it back.
  Real correctionSlop = 0.5e-6;
  /// CPs of one yarn this many elements apart or closer never collide (>= 1); raised per yarn to
  /// 1 + ceil(2 r0 / l0) (PairFilter).
  Index selfExclude = 1;
  /// A pair's static contact is carried to the next step, instead of tested again, while its CPs'
  /// sections are unchanged and its four nodes have moved together to within this distance [m] >= 0
  /// (0: every pair is tested every step). The gap follows the relative motion along the normal.
  Real cacheDistance = 1e-7;
  /// Contacts between yarns (CP-CP) on; false leaves only the contacts with rigid bodies (yarns then
  /// pass through each other: for scenes where only the projectile matters, and for comparisons).
  bool yarnContacts = true;
  /// Threads of the collision stage, in [0, 64]: 0 follows woven's count (woven::threads(): OpenMP's,
  /// i.e. OMP_NUM_THREADS or YADE's -j N, unless woven.set_threads forced one), >= 1 forces this
  /// count. Any count gives the same contacts and the same state, bit for bit (core/Parallel.hpp).
  int threads = 0;
  /// Row order of the impulse and projection sweeps. Every thread count gives the same bits in either.
  SweepOrder sweepOrder = SweepOrder::Sequential;

  Response response = Response::Impulse;
  /// Penalty stiffness k_p [N/m] > 0 (response Penalty): F = k_p delta on a contact overlapping by
  /// delta, yarn-yarn and yarn-body alike. 1e5 N/m: about the transverse stiffness of a KM2 yarn
  /// over a contact one yarn width long (E_T ~ 1.3 GPa x 0.1 mm ~ 1e5 N/m; docs/collisions.md),
  /// and stable (dt <= 2 sqrt(m_eff / k_p)) at the default ballistic time step.
  Real penaltyStiffness = 1e5;
  /// Normal damping ratio zeta in [0, 1) of the penalty contacts: c = 2 zeta sqrt(k_p m_eff).
  Real penaltyDamping = 0.0;
  Flattening flattening = Flattening::Geometric;
  /// Stiffness k_s [N/m] > 0 of one node section's spring (flattening Springs, paper Eq. 7): a section
  /// flattened by r0 eps pushes back with k_s r0 eps. 1e4 N/m: a tenth of k_p, since a yarn's
  /// filaments rearrange far more easily than a solid section compresses (not calibrated: the
  /// paper gives no k_i).
  Real sectionStiffness = 1e4;
  /// Where two yarns cross (model Gap; the paper model measures every pair its own way).
  Crossings crossings = Crossings::Persistent;
  /// Whether these parameters keep persistent crossings: the gap model's impulses (penalty forces
  /// and section springs act on CP pairs' four nodes: law/NormalForces), yarn contacts on.
  bool persistentCrossings() const {
    return crossings == Crossings::Persistent && model == ContactModel::Gap && response == Response::Impulse &&
           flattening != Flattening::Springs && yarnContacts;
  }

  /// Throws ParameterError naming the parameter and its allowed range.
  void validate() const;
};

}  // namespace woven
