// The collision stage of a step, top to bottom (docs/collisions.md), each stage in its own file:
//   refit      section frames and each CP's OBB, grown by its motion in the step (StageBroad.cpp)
//   crossings  the persistent crossings tracked by a Newton step from where they were, handed back
//              where they break, part, turn, kink or slide (StageCrossings.cpp, CrossingContacts)
//   broad      candidate CP pairs of the CPs that left their skin boxes, the crossings' own chord
//              pairs left out (StageBroad.cpp: grid, OBB tree or sweep and prune)
//   narrow     each candidate pair's contact: model Gap (the default) the gap function of the two
//              chains and its stencil (geom/GapFunction), model Paper the SAT (StagePairs.cpp);
//              the crossings measured and formed; each body part against its CPs (StageBodies.cpp)
//   respond    the sections flattened (StageSections.cpp), then the impulse rows of every contact
//              that can close within the step, warm-started and swept to solver_tolerance
//              (law/ImpulseLaw), the bodies' rows in the same solve; or the alternatives of
//              ContactParams::response / flattening (penalty forces, no flattening, section springs)
//   relax      after the drift, the position projection of what is left (afterDrift)
// The stage's memory (crossings, pairs' measure memory, carried contacts) travels in state files and
// snapshots (StageMemory.cpp). Rigid bodies (YADE's projectile, clamps: shape/RigidBody) join the
// same step and drift with their new velocities. The stage runs between the kick and the drift
// (ChainDynamics::StepHook) on x_n and v_{n+1/2}.
#pragma once
#include "collider/BodyCollider.hpp"
#include "collider/GridCollider.hpp"
#include "collider/SweepAndPrune.hpp"
#include "collider/YarnTreeCollider.hpp"
#include "dynamics/ChainDynamics.hpp"
#include "engine/CrossingContacts.hpp"
#include "geom/CPContact.hpp"
#include "geom/GapFunction.hpp"
#include "law/ImpulseLaw.hpp"
#include "law/PositionProjection.hpp"
#include "law/NormalForces.hpp"
#include <functional>
#include <string>

namespace woven {

enum class BroadPhase : std::uint8_t { YarnTree = 0, SweepAndPrune = 1, Grid = 2 };
/// "tree", "sap" or "grid"; throws ParameterError("broad_phase") otherwise.
BroadPhase broadPhaseByName(const std::string& name);

struct CollisionStats {
  // last step
  long candidates = 0;        ///< candidate pairs (of the last broad phase, which later steps may reuse)
  long contacts = 0;          ///< static + moving contacts
  long moving = 0;            ///< of which found by the moving test (not touching at the start)
  long cached = 0;            ///< of which carried from an earlier step (ContactParams::cacheDistance)
  long flattened = 0;         ///< contacts whose overlap was (partly) taken up by flattening
  int flattenPasses = 0;      ///< passes made
  // Explicit where the compiler would pad: the statistics are saved raw with the collision memory,
  // and padding left uninitialised made two saves of one run differ in their bytes.
  std::int32_t padding0_ = 0;
  ImpulseReport impulses;     ///< the impulse solve
  NormalForceReport forces;   ///< the penalty / section-spring forces (response penalty, flattening springs)
  Real springEnergy = 0;      ///< energy held in those springs at x_n [J] (1/2 k_p delta^2 + 1/2 k_s (r0 eps)^2)
  Real penetration = 0;       ///< largest overlap left after flattening and the check, before correction [m]
  Real correctionEnergy = 0;  ///< spring energy the positional correction put in [J] (model Paper)
  ProjectionReport projection;  ///< the position projection after the drift (model Gap)
  ProjectionReport check;     ///< the check before the rows (PositionProjection; sweeps 0: none this step)
  Real meanPenetration = 0;   ///< mean overlap of the contacts overlapping after flattening [m]
  Index deepestA = -1, deepestB = -1;  ///< the CPs of the deepest of them (-1: none)
  long overlapping = 0;       ///< contacts overlapping after flattening
  long bodyContacts = 0;      ///< CP-body contacts (static + moving)
  Real bodyPenetration = 0;   ///< largest CP-body overlap at the start of the step [m]
  Index deepestBodyCP = -1;   ///< the CP of that contact (-1: none)
  std::int32_t padding1_ = 0;  // (see padding0_)
  // since the start
  long steps = 0;
  long broadPhases = 0;       ///< broad phases run (the other steps reused the pairs: Verlet skin)
  long partialBroadPhases = 0;  ///< of which only for the CPs (grid) or yarns (OBB tree) that left their skin
  long renewed = 0;           ///< CPs the last step's partial broad phase collided again (0: none or a full phase)
  Real maxPenetration = 0;    ///< [m]
  /// Sums over the steps of the overlaps of the contacts overlapping after flattening and of their
  /// count [m, -], for the mean over contacts and time (yarn-yarn; bodies below).
  Real overlapSum = 0;
  long overlapCount = 0;
  Real bodyOverlapSum = 0;
  long bodyOverlapCount = 0;
  Real projectionEnergy = 0;  ///< spring energy the position projection put in since the start [J]
  long checks = 0;            ///< steps whose check moved nodes (ContactParams::projectionCheck)
  /// Largest overlap (yarn-yarn or CP-body) a check met, before its moves [m]: what the flattening
  /// left of the last projection's allowance (the overlaps above are measured after the check).
  Real maxChecked = 0;
  Real maxBodyPenetration = 0;  ///< [m]
  CrossingCounts crossings;   ///< the persistent crossings (ContactParams::crossings Persistent)
  long maxUnresolved = 0;     ///< most unresolved impulse rows in one step
  Real maxResidual = 0;       ///< [m/s]
  /// Since the start: impulse rows, sweeps and rows left unresolved, summed over the steps (the
  /// benches' fraction of unresolved rows over a run)
  long totalRows = 0, totalSweeps = 0, totalUnresolved = 0;
  /// wall time in refit, broad, narrow, respond (bodies included) and the position projection after
  /// the drift [s]
  Real seconds[5] = {0, 0, 0, 0, 0};
};

class CollisionStage : public StepHook {
 public:
  explicit CollisionStage(const ContactParams& p = ContactParams(), BroadPhase broad = BroadPhase::YarnTree);

  const ContactParams& params() const { return params_; }
  /// Validates first: nothing changes on bad input.
  void setParams(const ContactParams& p);
  BroadPhase broadPhase = BroadPhase::YarnTree;

  /// One collision pass (the StepHook of ChainDynamics). Returns the energy the impulses and the
  /// positional correction added [J].
  Real beforeDrift(Fabric& f, Real dt) override { return beforeDrift(f, dt, dt); }
  /// Drifts the rigid bodies with their new velocities, then the restitution pass of the impulse
  /// law (nothing for e = 0).
  Real afterDrift(Fabric& f, Real dt) override { return afterDrift(f, dt, true, true); }
  /// Spring substeps (FabricEngine::setSubsteps): the pass with the substep dt (its kick: the
  /// energy books) apart from the horizon, the time until the next pass, over which the boxes
  /// grow, the contacts are listed, the bodies' motion is predicted and the rows share their rooms.
  Real beforeDrift(Fabric& f, Real dt, Real horizon);
  /// A later substep of the same pass: the listed contacts measured again where the nodes and
  /// bodies are now (the same points and sections: remeasure, remeasureBody) and their rows solved
  /// again over what is left of the horizon, so that the springs between two passes cannot push a
  /// contact in (with the rows of the pass start only, the projection took it out and put 2-7 J
  /// into the compare's 5 J sphere scene). Returns the energy the impulses added [J].
  /// With slow nodes (setSlowNodes), only the contacts within two contacts of a fast node or a body
  /// are measured and solved again: the others' nodes have moved at constant velocity since the pass
  /// (multi-rate springs), which solved them for the whole step.
  Real resolveAgain(Fabric& f, Real dt, Real horizonLeft);
  /// Per node: 1 where only slow elements join it (FabricEngine::setMultiRate); empty: none.
  void setSlowNodes(std::vector<std::uint8_t> slow) { slowNode_ = std::move(slow), againStale_ = true; }
  /// The bodies drift over dt; then the restitution pass (after the pass's first substep: on the
  /// rows of the pass, whose approach it reverses) and the position projection (after its last).
  Real afterDrift(Fabric& f, Real dt, bool restitute, bool project);
  /// Whether a stage with these parameters can run with substeps (the gap model's impulses only:
  /// penalty forces and section springs would act over one substep, and the paper model's contacts
  /// are not measured again), and the allowed range named when it cannot.
  static bool allowsSubsteps(const ContactParams& p);
  static constexpr const char* kSubstepsRange =
      "1 with contact_model paper, response penalty or flattening springs (only the gap model's impulses substep)";
  /// Spring energy of the penalty contacts and section springs half way through the step's drift
  /// (law/NormalForces: the pair of the synchronised kinetic energy) [J].
  Real springEnergy() const override { return spring_; }
  Real takeProjectionEnergy() override {
    const Real e = projectionEnergy_;
    projectionEnergy_ = 0;
    return e;
  }
  Real takeBodyWork() override {
    const Real w = bodyWork_;
    bodyWork_ = 0;
    return w;
  }
  Real takeFrictionWork() override {
    const Real w = frictionWork_;
    frictionWork_ = 0;
    return w;
  }

  /// Rigid bodies colliding with the fabric. Each step they are taken at the start of the step
  /// (pose x_n, velocities v_{n+1/2}) and left at its end (x_{n+1}, drifted with the velocities the
  /// impulses gave): the adapter sets them before FabricEngine::step and reads them after.
  std::vector<RigidBody> bodies;
  const std::vector<BodyContact>& bodyContacts() const { return bodyContacts_; }
  /// Forgets what the stage carries between steps (persistent crossings, pairs' measure memory,
  /// carried contacts, the last body contacts): every pair is measured afresh at the next step.
  /// Called when the parameters change, a last good state is restored, or a state without the
  /// memory is loaded.
  void invalidateCache();
  /// What the stage carries between steps, as bytes (engine/StageMemory.cpp): state files and
  /// snapshots keep it, so that a save changes nothing and a continued run is the saving run.
  std::string memory() const;
  /// Takes memory() back for fabric f (as it stands: the state is applied first). Throws
  /// ParameterError("state") on bytes that are not such memory or do not fit f; returns false,
  /// changing nothing, for memory of another build's layout (the caller then forgets instead).
  bool setMemory(const Fabric& f, const std::string& bytes);
  /// setMemory's checks alone (nothing changes).
  void checkMemory(const Fabric& f, const std::string& bytes) const;
  /// Largest overlap of body k with any CP in the fabric as it stands [m] (<= 0: clear of it); moves
  /// nothing.
  Real bodyOverlap(Fabric& f, int k);
  BodyCollider bodyCollider;

  /// Flattens the sections of a fabric at rest until no overlap is left or every overlapping section
  /// is locked (no velocities or positions change): turns the circular sections of a freshly built
  /// weave into the flattened ones its crossings need. Returns the largest overlap left [m].
  Real settle(Fabric& f, int maxPasses = 100);

  /// Largest overlap between CPs (-gap of the static contacts) in the fabric as it stands [m]; moves
  /// nothing (the section frames it refits are put back; measured by a copy of the stage).
  Real overlap(Fabric& f);

  const std::vector<CPContact>& contacts() const { return contacts_; }
  /// The persistent crossings (empty unless ContactParams::persistentCrossings()).
  const CrossingContacts& crossings() const { return crossings_; }
  const std::vector<OBB>& bounds() const { return bounds_; }
  const std::vector<CPPair>& candidates() const { return pairs_; }
  /// Refits the bounds and lists the candidate pairs of the given broad phase at the current state
  /// (dt = 0, no skin; the stage's own pairs are untouched): for tests and benchmarks.
  void candidatePairs(Fabric& f, BroadPhase which, std::vector<CPPair>& out);

  CollisionStats stats;
  YarnTreeCollider tree;
  SweepAndPrune sap;
  GridCollider grid;

 private:
  void refit(Fabric& f, Real dt);
  /// How far a contact of the position projection after the drift may move a node [m]
  /// (projection_max_move; 0 without it): boxes grow by it and pairs within it are listed, so that
  /// no single push carries a node into a pair nobody measured. A node pushed by several contacts
  /// (up to kProjectionTravel x projection_max_move) may reach one beyond; the next step lists it
  /// and its check takes the overlap out before the rows. Listed to kProjectionTravel x, the side-by-
  /// side neighbours of a tight weave (30-80 um apart) were measured at every step for pushes that,
  /// with the projection's rebound (kRebound), are a fraction of a micrometre.
  Real projectionReach(Real dt) const {
    return dt > 0 && params_.projectionSweepCount() > 0 ? params_.projectionMaxMove : 0.0;
  }
  void broad(const Fabric& f);
  /// Steps of its mean velocity a renewed CP's skin box reaches ahead (skinBox).
  static constexpr Real kSkinSteps = 8;
  OBB skinBox(const Fabric& f, Index e) const;
  void narrow(const Fabric& f, Real dt);
  /// The persistent crossings' part of a pass: tracked before the broad phase (trackCrossings),
  /// formed from the general contacts and measured after the narrow phase (measureCrossings).
  void trackCrossings(const Fabric& f);
  void measureCrossings(const Fabric& f, Real dt, bool formNew);
  void seedReturned(const Fabric& f);
  // A pair's memory (model Gap; kept while the broad phase keeps the pair, forgotten with the cache):
  // its kind (Side / Cross hysteresis), the side its normal points to, and the measure its sections
  // claimed (GapFunction.hpp, capMeasure). Apart from PairCache: small, and only this is remapped.
  struct PairMemo {
    bool memo = false, side = false;
    // Returned by a persistent crossing and not measured since: a point without a remembered
    // measure may claim only the room its axes leave (capMeasure at 0), so that the chords taking
    // over from the crossing's curves do not start in an overlap the curves did not have.
    bool held = false;
    // Its contact points at the last narrow phase that measured it (1 or 2; 0: measure forgotten,
    // the pair was not measured since its boxes parted): their places sA, sB, the normal and the
    // sections' measure hA + hB [m] at each.
    int memoPoints = 0;
    Real memoS[2] = {0, 0}, memoT[2] = {0, 0}, memoMeasure[2] = {0, 0};
    Vec3 memoNormal[2] = {Vec3::Zero(), Vec3::Zero()};
    // The screen (narrow): the axes' distance less both CPs' widest sections at the MCD when the
    // pair was last evaluated [m] (-inf: never), and their odometers' sum then [m].
    Real clear = -INFINITY, odometer = 0;
    /// The measure forgotten (the pair not measured since its boxes parted); the screen kept.
    void forget() {
      const Real c = clear, o = odometer;
      *this = PairMemo();
      clear = c, odometer = o;
    }
  };
  // A pair's last static contact (model Paper, contact_cache > 0: ContactParams::cacheDistance).
  struct PairCache {
    bool valid = false;
    long clock = 0;     // narrow phase that measured it
    CPContact contact;
    Vec3 x[4];          // the four node positions then [m]
  };
  bool reuse(const Fabric& f, std::size_t k, CPContact& c) const;
  struct Memory;
  Memory parseMemory(const Fabric& f, const std::string& bytes) const;
  void remapCache(bool caching, bool gapModel);
  void narrowBodies(const Fabric& f, Real dt);
  /// The flattening passes; with bodyDt >= 0 (a step's dt) the body contacts flatten the sections
  /// they press too, and are measured again after each pass.
  int flatten(Fabric& f, int maxPasses, Real bodyDt = -1);
  void checkOverlaps(Fabric& f, Real dt);  // the check before the rows (ContactParams::projectionCheck)
  void measureBodies(const Fabric& f, Real dt);
  std::function<Real(const CPContact&)> capacityOf(const Fabric& f) const;
  bool crossesSteeply(const Fabric& f, const CPContact& c) const;
  bool measuresThickness(const Fabric& f, const CPContact& c) const;
  Real capacityOne(const Fabric& f, const CPContact& c, bool sideB, const std::vector<Real>* flat = nullptr) const;
  void restoreSections(Fabric& f);
  Real addSectionSprings(const Fabric& f);

  ContactParams params_;
  PairFilter filter_;
  Vec3Array tangent_, dirSum_;
  std::vector<OBB> bounds_, grown_, skinBoxes_;  // skinBoxes_: grown_ + skin at the last broad phase
  bool pairsValid_ = false;
  std::vector<Real> grow_, flatBefore_, widest_;  // widest_: per node, the major semi-axis (model Gap)
  ChordFrames chords_;                           // narrow (model Gap): each CP's unit chord and length
  std::vector<Real> speed_;                      // refit: each CP's faster node's speed [m/s] (boxes, narrow)
  Real horizon_ = 0;                             // refit: the step its boxes were grown for [s] (0: static)
  Vec3Array lastPos_;                            // refit: each node's position at the last pass [m]
  std::vector<Real> travelled_, odometer_;       // per node the path travelled since the start, per CP its nodes' sum [m]
  std::vector<Real> widestAtMcd_;                // narrow (model Gap): each CP's widest semi-axis at the MCD [m]
  std::vector<CPPair> pairs_;
  std::vector<CPContact> contacts_;
  std::vector<BodyCandidate> bodyPairs_;
  std::vector<BodyContact> bodyContacts_;
  std::vector<BodyContact> heldBody_;                          // the last step's, for the measure memory
  std::vector<std::pair<std::uint64_t, std::size_t>> heldKeys_;  // (CP, body, part) -> index in heldBody_
  std::size_t heldFor_ = 0;                                       // the body count they were measured with
  bool forgetHeld_ = false;                                       // invalidateCache: no memory at the next step
  Real bodyWork_ = 0;
  Real frictionWork_ = 0;  // the impulses' tangential parts took since the last take [J]
  std::vector<std::vector<CPContact>> slices_;  // narrow-phase output per chunk of pairs
  std::vector<long> reused_;                    // carried contacts per chunk of pairs
  std::vector<Real> capacity_;                  // flatten: both CPs' flattening capacity per contact [m]
  std::vector<std::vector<Index>> flattenChunks_;  // flatten: the contacts that can flatten, per chunk
  std::vector<Index> flattenList_;                 // and all of them in order
  // beforeDrift's statistics of the contacts per fixed chunk: the deepest overlap (its first
  // contact), the moving count, the overlaps in order
  struct OverlapScan {
    Real deepest = 0;
    Index at = -1;
    long moving = 0;
  };
  std::vector<OverlapScan> scanChunks_;
  std::vector<std::vector<Real>> overlapChunks_;
  std::vector<Real> overlapGaps_;
  std::vector<std::uint8_t> dirty_, dirtyYarn_, outside_;
  std::vector<std::uint8_t> leftSkin_;  // refit: per CP, its grown box left its skin box (or has none)
  std::vector<CPPair> keptPairs_, freshPairs_, cachePairs_;
  std::vector<std::vector<CPPair>> keptChunks_;  // the kept pairs of each fixed chunk (broad)
  std::vector<PairCache> cache_, cacheOld_;  // model Paper with a contact cache
  std::vector<PairMemo> memo_, memoOld_;     // model Gap
  std::vector<long> sectionStamp_;  // per CP: narrow phase in which its sections last changed
  long cacheClock_ = 0;
  bool pairsChanged_ = false;
  std::vector<std::uint8_t> slowNode_, nearFast_, again_;  // resolveAgain: slow nodes, the marks, the contacts solved
  bool againStale_ = true;                                 // again_ not yet marked for this pass's contacts
  CrossingContacts crossings_;
  std::vector<std::uint8_t> renew_;  // per CP: its pairs return to the general pipeline (a crossing left it)
  std::vector<Real> impulses_;       // per contact: its row's impulse after the solve (the crossings' warm start)
  std::vector<std::uint8_t> rowable_, rowAgain_;  // per contact: it can close its gap within the step (markRowable)
  std::vector<Real> passMove_;         // per node: its travel since the pass measured the contacts [m]
  bool passMoveValid_ = false;         // ... and no check moved a node in between
  const std::uint8_t* markRowable(Real horizon);
  Real fastestNear(const Fabric& f, Index e) const;
  ImpulseLaw law_;
  PositionProjection projector_;
  Real projectionEnergy_ = 0;
  NormalForces forces_;
  Real spring_ = 0;
  std::vector<Real> restFlat_, nodeWeight_;  // flattening Springs: each node's eps at the first step
  Vec3Array restDir_;
};

}  // namespace woven
