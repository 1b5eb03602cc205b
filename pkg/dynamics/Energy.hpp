// Energy books of the chain dynamics. All in joules. "work" is what the loads (kinematic nodes,
// point forces, body force) and the rigid bodies' impulses put in; the balance
// kinetic + elastic + damped + contact + friction + spring + released + projection = initial + work
// holds to the integrator's O(dt^2) accuracy (the position projection's moves are booked in
// `projection`; the paper model's pre-drift corrections are booked in `contact` when made, but the
// step drifts on forces of the uncorrected positions: docs/collisions.md).
#pragma once
#include "core/Types.hpp"

namespace woven {

struct EnergyBooks {
  Real kinetic = 0;     ///< sum 1/2 m v^2 at the current integer step [J]
  Real elastic = 0;     ///< sum 1/2 K (l - l0)^2 over taut elements [J]
  Real damped = 0;      ///< energy dissipated by the element dashpots since the start [J]
  Real work = 0;        ///< work done on the fabric by loads and by rigid bodies' impulses since the start [J]
  Real bodyWork = 0;    ///< of which by the rigid bodies (YADE bodies coupled to the fabric) [J]
  Real contact = 0;     ///< energy taken out by the contact stage since the start [J] (impulses take, corrections give)
  /// Of the impulses' take, what their tangential (Coulomb friction) parts took since the start [J]:
  /// each row's final tangential impulse of a solve against its mean relative velocity over the solve
  /// (law/ImpulseLaw.hpp); `contact` holds the rest (the normal parts).
  Real friction = 0;
  Real contactInput = 0;  ///< energy the contact stage put in, summed step by step [J] (>= 0)
  /// Energy held now in the contact springs of a force-based response (penalty contacts 1/2 k_p delta^2,
  /// section springs 1/2 k_s (r0 eps)^2: docs/collisions.md); what they held at the first step is in initial [J].
  Real spring = 0;
  Real released = 0;    ///< elastic energy of broken elements, released at their break [J]
  /// Energy taken out by the position projection of the contact model `gap` since the start [J]
  /// (negative: the moves put spring energy in; law/PositionProjection).
  Real projection = 0;
  Real initial = 0;     ///< kinetic + elastic at step 0 (+ the contact springs' energy then) [J]

  Real total() const { return kinetic + elastic + damped + contact + friction + spring + released + projection; }
  /// (kinetic + elastic + damped + contact + friction + spring + released + projection) - (initial + work) [J]
  Real balanceError() const { return total() - initial - work; }
};

}  // namespace woven
