#include "law/ContactParams.hpp"
#include "core/Errors.hpp"
#include <cmath>

namespace woven {

ContactModel contactModelByName(const std::string& name) {
  if (name == "gap") return ContactModel::Gap;
  if (name == "paper") return ContactModel::Paper;
  throw ParameterError("contact_model", "'" + name + "'",
                       "'gap' (gap functions, exact gradient rows, position projection) or 'paper' (Sections 4-5)");
}

Crossings crossingsByName(const std::string& name) {
  if (name == "persistent") return Crossings::Persistent;
  if (name == "chords") return Crossings::Chords;
  throw ParameterError("crossings", "'" + name + "'",
                       "'persistent' (one contact per crossing, carried between steps) or 'chords' (every CP pair "
                       "measured afresh: four chord-pair contacts per crossing)");
}

SweepOrder sweepOrderByName(const std::string& name) {
  if (name == "coloured") return SweepOrder::Coloured;
  if (name == "sequential") return SweepOrder::Sequential;
  if (name == "blocked") return SweepOrder::Blocked;
  throw ParameterError("sweep_order", "'" + name + "'",
                       "'coloured' (colour by colour on the threads), 'sequential' (contact order, serial) or "
                       "'blocked' (slabs of the ply at once on the threads, then the rows across them)");
}

Response responseByName(const std::string& name) {
  if (name == "impulse") return Response::Impulse;
  if (name == "penalty") return Response::Penalty;
  throw ParameterError("response", "'" + name + "'", "'impulse' (Eq. 5 impulses) or 'penalty' (spring forces k_p delta)");
}

Flattening flatteningByName(const std::string& name) {
  if (name == "geometric") return Flattening::Geometric;
  if (name == "none") return Flattening::None;
  if (name == "springs") return Flattening::Springs;
  throw ParameterError("flattening", "'" + name + "'",
                       "'geometric' (free up to the MCD), 'none' (sections fixed) or 'springs' (Eq. 7 section springs)");
}

void ContactParams::validate() const {
  require(std::isfinite(restitution) && restitution >= 0 && restitution <= 1, "restitution", restitution, "[0, 1]");
  require(std::isfinite(friction) && friction >= 0 && friction <= 2, "friction", friction,
          "[0, 2] (Coulomb coefficient between yarns)");
  require(std::isfinite(bodyFriction) && bodyFriction >= 0 && bodyFriction <= 2, "body_friction", bodyFriction,
          "[0, 2] (Coulomb coefficient between a rigid body and the yarns)");
  require(std::isfinite(mcd) && mcd > 0 && mcd < 1, "mcd", mcd, "(0, 1) (maximum cross-sectional deformation)");
  // Lengths bounded at sizes past any use (a yarn is ~0.1 mm thick): a skin of 1e300 m made every
  // CP pair a candidate, the pair list and its memory quadratic in the CPs (scripts/fuzz.py found
  // such values taken).
  require(std::isfinite(margin) && margin >= 0 && margin <= 1e-3, "margin", margin, "[0, 1e-3] m");
  require(std::isfinite(skin) && skin >= 0 && skin <= 1e-2, "skin", skin, "[0, 1e-2] m");
  require(std::isfinite(tolerance) && tolerance > 0, "tolerance", tolerance, "(0, inf) m/s");
  require(maxIterations >= 1, "max_iterations", maxIterations, "[1, inf)");
  require(std::isfinite(solverTolerance) && solverTolerance >= 0 && solverTolerance <= 1e-3, "solver_tolerance",
          solverTolerance, "[0, 1e-3] m (0: the tolerance in m/s alone)");
  require(flattenPasses >= 1, "flatten_passes", flattenPasses, "[1, inf)");
  require(std::isfinite(positionCorrection) && positionCorrection >= 0 && positionCorrection <= 1,
          "position_correction", positionCorrection, "[0, 1]");
  require(std::isfinite(correctionSlop) && correctionSlop >= 0 && correctionSlop <= 1e-3, "correction_slop",
          correctionSlop, "[0, 1e-3] m");
  require(std::isfinite(cacheDistance) && cacheDistance >= 0 && cacheDistance <= 1e-3, "contact_cache", cacheDistance,
          "[0, 1e-3] m (0: off)");
  require(threads >= 0 && threads <= 64, "threads", threads, "[0, 64] (0: OpenMP's count)");
  require(static_cast<int>(sweepOrder) <= 2, "sweep_order", static_cast<int>(sweepOrder), "'coloured', 'sequential' or 'blocked'");
  require(std::isfinite(penaltyStiffness) && penaltyStiffness > 0, "penalty_stiffness", penaltyStiffness, "(0, inf) N/m");
  require(std::isfinite(penaltyDamping) && penaltyDamping >= 0 && penaltyDamping < 1, "penalty_damping", penaltyDamping,
          "[0, 1) (damping ratio)");
  require(std::isfinite(sectionStiffness) && sectionStiffness > 0, "section_stiffness", sectionStiffness, "(0, inf) N/m");
  require(static_cast<int>(response) <= 1, "response", static_cast<int>(response), "'impulse' or 'penalty'");
  require(static_cast<int>(flattening) <= 2, "flattening", static_cast<int>(flattening), "'geometric', 'none' or 'springs'");
  require(static_cast<int>(model) <= 1, "contact_model", static_cast<int>(model), "'gap' or 'paper'");
  require(static_cast<int>(crossings) <= 1, "crossings", static_cast<int>(crossings), "'persistent' or 'chords'");
  require(!(response == Response::Penalty && friction > 0), "friction", friction,
          "0 with response 'penalty' (Coulomb friction acts in the impulse rows only); [0, 2] with response 'impulse'");
  require(!(response == Response::Penalty && bodyFriction > 0), "body_friction", bodyFriction,
          "0 with response 'penalty' (Coulomb friction acts in the impulse rows only); [0, 2] with response 'impulse'");
  require(projectionSweeps >= -1 && projectionSweeps <= 50, "projection_sweeps", projectionSweeps, "[0, 50], or -1 (auto)");
  require(!(projectionSweeps > 0 && (model != ContactModel::Gap || response != Response::Impulse)), "projection_sweeps",
          projectionSweeps, "0 or -1 (auto) with contact_model 'paper' or response 'penalty'; [1, 50] only with "
          "contact_model 'gap' and response 'impulse'");
  require(std::isfinite(projectionSlop) && projectionSlop >= 0 && projectionSlop <= 1e-3, "projection_slop", projectionSlop,
          "[0, 1e-3] m");
  require(std::isfinite(projectionMaxMove) && projectionMaxMove > 0 && projectionMaxMove <= 1e-3, "projection_max_move",
          projectionMaxMove, "(0, 1e-3] m");
  require(projectionCheck == -1 || (std::isfinite(projectionCheck) && projectionCheck >= 0 && projectionCheck <= 1e-3),
          "projection_check", projectionCheck, "[0, 1e-3] m, or -1 (no check)");
  require(selfExclude >= 1, "self_exclude", selfExclude, "[1, inf) elements (1: CPs sharing a node)");
}

}  // namespace woven
