"""Overlap between yarns and between the projectile and the yarns, as every scene reports it.

The energy books cannot see yarns passing into each other, so every scene measures the overlap:
the depth of the contacts that still overlap after the step's flattening and its check (the
projection of what the flattening left, before the rows), on the contact model's own gap functions
(docs/collisions.md), relative to the yarn thickness. `OverlapMeter.sample()` is called once per
step; `summary()` gives the largest and mean overlaps (the mean over the contacts in overlap and
over the steps), the energy the position projection put in (the check's moves included), and what
the check met: the largest overlap the flattening left before the check's moves and the steps it
moved nodes in.
"""


class OverlapMeter:
    def __init__(self, engine, thickness):
        self.engine, self.thickness = engine, float(thickness)
        self.max_before_break = 0.0
        self.body_max_before_break = 0.0
        self.steps = 0

    def sample(self):
        """Once per step (after it): keeps the largest overlaps seen before the first broken element."""
        s = self.engine.collision_stats()
        self.steps += 1
        if self.engine.broken_elements == 0:
            self.max_before_break = max(self.max_before_break, s['penetration'])
            self.body_max_before_break = max(self.body_max_before_break, s['body_penetration'])

    def summary(self):
        """dict of overlaps [m] and relative to the yarn thickness [-], and the projection's energy [J]."""
        s = self.engine.collision_stats()
        E = self.engine.energy()
        t = self.thickness
        mean = s['overlap_sum'] / s['overlap_count'] if s['overlap_count'] else 0.0
        body_mean = s['body_overlap_sum'] / s['body_overlap_count'] if s['body_overlap_count'] else 0.0
        return {
            'yarn_max': s['max_penetration'], 'yarn_max_rel': s['max_penetration'] / t,
            'yarn_mean': mean, 'yarn_mean_rel': mean / t,
            'yarn_max_before_break_rel': self.max_before_break / t,
            'body_max': s['max_body_penetration'], 'body_max_rel': s['max_body_penetration'] / t,
            'body_mean': body_mean, 'body_mean_rel': body_mean / t,
            'body_max_before_break_rel': self.body_max_before_break / t,
            'contacts_in_overlap_per_step': s['overlap_count'] / max(1, s['steps']),
            'projection_energy_in': -E['projection'],
            'checked_max': s['max_checked'], 'checked_max_rel': s['max_checked'] / t, 'check_steps': s['checks'],
            'thickness': t,
        }


UNITS = {'yarn_max': 'm', 'yarn_mean': 'm', 'body_max': 'm', 'body_mean': 'm', 'thickness': 'm',
         'checked_max': 'm (largest overlap the flattening left and the check took out, before its moves)',
         'check_steps': 'steps whose check moved nodes',
         'projection_energy_in': 'J (spring energy the position projection put in; < 0: took out)'}
