"""A finer time step once a scene's energy books drift (scripts/ballistic.py's `energy_guard`).

Tension-only yarn chains gain energy through slack/taut switching near dt_crit (docs/design.md).
After breaks at fine resolution the free pieces flap for tens of microseconds and a scene's balance
error grows: a 6 mm cube at 50 m/s on the 12.7 mm ply at 4 CPs per crossing reached 5.6 % by
100 us at 0.7 dt_crit, 2.2 % at 0.5 and 0.35 % at 0.35. A finer step from the first break on would
cost half again the steps of every perforating run (the default impact breaks half way through), so
the guard refines only where the books show the drift: once the balance error passes `limit` (a
fraction of the scene's energy scale), O.dt becomes `safety` * dt_max (dt_max = substeps x dt_crit)
for the rest of the run. The fabric's integrator takes the change (its kick spans half the old and
half the new step).
"""
from yade.wrapper import Omega

_O = Omega()


class EnergyGuard:
    def __init__(self, engine, limit, safety):
        """engine: the woven.FabricEngine; limit: balance error that refines the step, >= 0 (0: off);
        safety: O.dt = safety * dt_max once refined, in (0, 1]."""
        if not (0 <= limit < 1):
            raise ValueError('energy_guard = %r is invalid: allowed [0, 1) (0: off)' % (limit,))
        if not (0 < safety <= 1):
            raise ValueError('guard_safety = %r is invalid: allowed (0, 1]' % (safety,))
        self.engine, self.limit, self.safety = engine, float(limit), float(safety)
        self.refined_at = None  # simulated time of the refinement [s]
        self.dt_before = None

    def smallest_dt(self):
        """The smallest O.dt the run can take [s] (to size its step budget)."""
        return min(_O.dt, self.safety * self.engine.dt_max) if self.limit > 0 else _O.dt

    def check(self, balance):
        """Refines O.dt when |balance| passes the limit (once); returns the factor by which the step
        shrank now (1: unchanged)."""
        if self.limit <= 0 or self.refined_at is not None or not abs(balance) > self.limit:
            return 1.0
        dt = self.safety * self.engine.dt_max
        if dt >= _O.dt:
            self.refined_at = _O.time  # already that fine
            return 1.0
        self.refined_at, self.dt_before = _O.time, _O.dt
        _O.dt = dt
        return self.dt_before / dt

    def summary(self):
        return {'energy_guard': self.limit, 'guard_safety': self.safety, 'refined_at': self.refined_at,
                'dt_before': self.dt_before, 'dt_after': _O.dt if self.refined_at is not None else None}
