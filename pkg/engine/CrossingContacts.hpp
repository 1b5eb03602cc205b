// Persistent crossings (contact model `gap`, ContactParams::crossings Persistent; docs/collisions.md,
// "Persistent crossings"). Where two yarns cross, one contact stands for the crossing, carried from
// step to step with its sliding coordinates (a place on each yarn: geom/YarnCurve.hpp), its side,
// its sections' measure memory and its last impulse (the rows' warm start), in the manner of Cirio
// et al.'s persistent crossing nodes (SIGGRAPH Asia 2014) and Kaldor et al.'s contacts reused while
// coherent (SIGGRAPH 2010). The general pipeline (broad and narrow phases of CP pairs) keeps every
// other contact, the rigid bodies' and the pairs a crossing hands back.
//
// Each step, before the broad phase (track): one Newton step of the closest points of the two
// yarns' smooth centre lines from where the crossing was (it walks into the neighbouring CP when
// the point leaves its CP), then the hand-back rules, each returning the crossing's pairs to the
// general pipeline:
//   Break       a CP the crossing's curves read (the point's CP and its neighbours), or any CP of its
//               footprint, is broken;
//   Separation  the chains' axes at the points are farther apart than the two sections' radii at
//               rest beyond touching (the yarns have parted: their pairs are measured as any);
//   Turn        the yarns cross at less than 45 degrees (kTurnDeg; its measure, the half-thicknesses,
//               holds above that: GapFunction.hpp) or the closest points are no longer defined;
//   Kink        a chain turns by more than kKinkDeg at a node of the point's CP: the chords'
//               closest approach then lies beyond the rounded corner, on one of the four chord
//               pairs (a node whose chords turn away from the other yarn by 2 alpha leaves them
//               h (1 - cos alpha) closer than the node: 1 % at a built crossing, 7.6 % at 45
//               degrees), and the lines come closest in as many places: the chords are the yarn;
//               or a CP of its footprint turns from the point's by more than kFoldDeg (a piece
//               folded inside the footprint, whose pairs the general pipeline skips);
//   Slide       a point leaves its yarn or jumps (more than a quarter CP in a step: the curves'
//               closest approach moved elsewhere), or its footprint lands on another crossing of
//               the same two yarns (a folded piece's two crossings met) or finds no room.
// After the general narrow phase (form): a contact of two yarns' CPs that cross steeply (kFormDeg,
// above kTurnDeg: hysteresis), whose chains turn by at most kFormKinkDeg there and by at most
// kKinkDeg at the CP beside each place (toward its nearer node: where tracking would walk it),
// whose CPs and neighbours are alive and whose pair no crossing covers
// forms a crossing at the lines' closest points near it, if they lie on the contact's side, its
// measure memory holding its gap at the contact's where the lines read less: a built weave's
// crossings at the first step, a crossing again once its yarns return. Its chord pairs' contacts
// leave that step's list.
// The crossings' contacts (measure) are listed, like any, when they can close within the step.
#pragma once
#include "collider/CandidatePairs.hpp"
#include "collider/CrossingFootprints.hpp"
#include "core/Parallel.hpp"
#include "geom/CPContact.hpp"
#include "geom/YarnCurve.hpp"
#include "law/ContactParams.hpp"
#include <algorithm>
#include <cstdint>
#include <vector>

namespace woven {

struct Crossing {
  YarnPlace a, b;               ///< its sliding coordinates; a's yarn is the lower index (a.cp < b.cp)
  Vec3 normal = Vec3::UnitZ();  ///< the side B lies on, seen from A (unit; its last contact's normal)
  Real measure = -1;            ///< its sections' measure hA + hB at the last step [m] (< 0: none yet)
  Real lambda = 0;              ///< its row's normal impulse at the last step [N s] (warm start)
  Index fa0 = 0, fa1 = -1, fb0 = 0, fb1 = -1;  ///< its footprint: CPs [fa0, fa1] of A, [fb0, fb1] of B
  Real fsA = 0, fsB = 0;        ///< the places' s the footprint was drawn at
  Real apart = 0;               ///< the lines' distance at the last places, at the last track's positions [m]
};

enum class HandBack : std::uint8_t { Break = 0, Separation = 1, Turn = 2, Slide = 3, Kink = 4 };

/// The CPs of a crossing handed back (or left behind by its footprint) in a step, with its side:
/// the general pipeline's pairs between them start from it (CollisionStage's PairMemo::held).
struct ReturnedFootprint {
  Index a0, a1, b0, b1;
  Vec3 normal;
};

struct CrossingCounts {
  long live = 0;                     ///< crossings now
  long listed = 0;                   ///< of which listed as contacts in the last step
  long formed = 0;                   ///< since the start
  long handedBack[5] = {0, 0, 0, 0, 0};  ///< since the start, by rule (HandBack)
  long moved = 0;                    ///< footprint moves since the start (a point walked into another CP)
};

class CrossingContacts {
 public:
  static constexpr Real kTurnDeg = 45;  ///< a crossing is handed back below this angle [deg]
  static constexpr Real kFormDeg = 50;  ///< and formed only at this angle or more [deg]
  /// A crossing is handed back where a chain turns by more than this at a node of the point's CP
  /// [deg], and formed only at kFormKinkDeg or less: a built weave's chains turn by 2 x the crimp
  /// angle at a crossing node (16 degrees in KM2 706 at one CP per span).
  static constexpr Real kKinkDeg = 35, kFormKinkDeg = 25;
  /// ... and where a CP of its footprint is broken or turned from the point's CP by more than this
  /// [deg] (a piece folded or flying inside the footprint, whose pairs the general pipeline skips).
  static constexpr Real kFoldDeg = 45;

  /// No crossings, for fabric f's CPs.
  void reset(const Fabric& f);
  bool empty() const { return all_.empty(); }
  const std::vector<Crossing>& crossings() const { return all_; }
  const CrossingFootprints& footprints() const { return foot_; }
  /// The footprints the last track() returned to the general pipeline.
  const std::vector<ReturnedFootprint>& returned() const { return returned_; }

  /// Before the broad phase: each crossing's Newton step and the hand-back rules (above). Sets
  /// renew[e] = 1 for each CP of a footprint that shrank or went (their pairs return to the general
  /// pipeline: the broad phase collides them again). Returns true when a footprint moved onto new
  /// CPs (their pairs must leave the candidate list: exclude).
  /// `chord`: every CP's unit chord at the current positions.
  bool track(const Fabric& f, const ContactParams& p, const Vec3Array& chord, std::vector<std::uint8_t>& renew);
  /// After the general narrow phase: crossings formed from its contacts (above). Returns true when
  /// one formed.
  bool form(const Fabric& f, const std::vector<CPContact>& contacts, const ContactParams& p, const Vec3Array& chord);
  /// Removes from `pairs` (or contacts) those a crossing covers, keeping the order.
  void exclude(std::vector<CPPair>& pairs);
  void exclude(std::vector<CPContact>& contacts) const;
  /// Each crossing's contact at the current positions (the sections' measure capped by its memory,
  /// which it then keeps with its side); those with gap <= reach(contact) appended to `out`.
  template <class Reach>
  void measure(const Fabric& f, const ContactParams& p, Reach&& reach,
               std::vector<CPContact>& out);
  /// The rows' impulses of the listed contacts (their CPContact::crossing) after the solve, for the
  /// next step's warm start; a crossing not listed starts from 0.
  void keepImpulses(const std::vector<CPContact>& contacts, const std::vector<Real>& lambda);

  /// The state a saved run continues from (StateIO, Snapshot): the crossings in order. set() checks
  /// every crossing against f first (ParameterError "state") and rebuilds the footprints.
  void set(const Fabric& f, const std::vector<Crossing>& all, const ContactParams& p);

  CrossingCounts counts;

 private:
  // One crossing's contact at the current positions, its memory applied and kept.
  void measureOne(const Fabric& f, Index id, const ContactParams& p, CPContact& c);
  void footprint(const Fabric& f, const Crossing& x, const ContactParams& p, Index& a0, Index& a1, Index& b0,
                 Index& b1) const;
  static int usable(const Fabric& f, const Vec3Array& chord, Index e, Real kinkCos);
  static bool usableBeside(const Fabric& f, const Vec3Array& chord, const YarnPlace& q);
  static int whole(const Fabric& f, const Vec3Array& chord, Index lo, Index hi, Index e);
  void handBack(Index id, HandBack why, std::vector<std::uint8_t>& renew);
  // What track decides for one crossing: its new places and their lines' distance, a hand-back
  // rule (verdict 1 + HandBack) or 0, and unless its footprint still holds (same) the new one.
  struct Step {
    YarnPlace a, b;
    Real apart = 0;
    int verdict = 0;
    bool same = true;
    Index fa0 = 0, fa1 = -1, fb0 = 0, fb1 = -1;
  };
  Step stepOne(const Fabric& f, const ContactParams& p, const Vec3Array& chord, const Crossing& x) const;
  std::vector<Crossing> all_;
  std::vector<std::uint8_t> gone_;  // track: the crossings handed back this step
  std::vector<ReturnedFootprint> returned_;
  CrossingFootprints foot_;
  std::vector<Step> steps_;                     // track: each crossing's step
  std::vector<std::vector<CPPair>> keptPairs_;  // exclude: each chunk's pairs kept
  std::vector<std::vector<CPContact>> slices_;  // measure: each chunk's listed contacts
};

// Fixed chunks of the crossings (threads; measureOne writes only its own crossing), appended in
// chunk order: the same list for any thread count.
template <class Reach>
void CrossingContacts::measure(const Fabric& f, const ContactParams& p, Reach&& reach,
                               std::vector<CPContact>& out) {
  constexpr Index kChunk = 512;
  const Index n = static_cast<Index>(all_.size());
  slices_.resize(static_cast<std::size_t>(chunkCount(n, kChunk)));
  parallelFor(static_cast<Index>(slices_.size()), 1, threads(), [&](Index t) {
    std::vector<CPContact>& listed = slices_[t];
    listed.clear();
    CPContact c;
    for (Index id = t * kChunk, end = std::min(n, id + kChunk); id < end; ++id) {
      measureOne(f, id, p, c);
      if (c.gap <= reach(c)) listed.push_back(c);
    }
  });
  counts.listed = 0;
  for (const std::vector<CPContact>& listed : slices_) {
    out.insert(out.end(), listed.begin(), listed.end());
    counts.listed += static_cast<long>(listed.size());
  }
}

}  // namespace woven
