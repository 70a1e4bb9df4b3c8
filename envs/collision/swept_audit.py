"""The collision checker's swept (tunneling) audit (a part of :class:`~clutter_gym.collision.checker.CollisionChecker`:
it keeps the shapes' poses at the last check and bounds its sweeps with the checker's :class:`NearestSearch`).

A shape that moved faster than ``swept_speed`` is swept from its previous pose on the screw motion to its pose now
(:mod:`.sweep`: conservative advancement on FCL's exact distance) against the obstacles near its path; the cheap
filters first (the end bounds, the cones about start and end, the enclosing ball along the path), the exact sweep only
for the pairs they leave.
"""

from __future__ import annotations

import fcl
import numpy as np

from clutter_gym.collision.kernels import shape_travel
from clutter_gym.collision.nearest import BOUND_SLACK, NearestSearch
from clutter_gym.collision.sweep import ScrewMotion, time_of_impact

#: Times along a swept shape's motion at which its enclosing ball is measured before the exact sweep (0 and 1 included)
BALL_SAMPLES = 9


class SweptAudit:
    """Counts the swept hits a step's end-of-step check does not see (:meth:`count`); it bounds the obstacles near a
    sweep with the nearest search's :meth:`~NearestSearch.lower_bounds`.

    Args:
        search: the checker's nearest search (its model, moving shapes, obstacles and bounds).
        swept_speed: shapes faster than this (m/s) are swept; ``inf`` turns the audit off.
        dt: time between two checks, seconds.
    """

    def __init__(self, search: NearestSearch, swept_speed: float, dt: float) -> None:
        self.search, self.swept_speed, self.dt = search, swept_speed, dt
        shapes = search.model.shapes
        self._radii = np.array([s.radius for s in shapes])  # about each shape's origin
        self._ball_offsets = np.array([s.bounding_ball[0] for s in shapes], dtype=float).reshape(-1, 3)
        self._sweepers = [fcl.CollisionObject(s.hull or s.geometry, fcl.Transform()) for s in shapes]
        #: the shapes' (positions, rotations) at the last check; None after a teleport (nothing to sweep from)
        self.previous: tuple[np.ndarray, np.ndarray] | None = None

    def count(self, candidates: np.ndarray, bound: np.ndarray, within: float, touching_before: set[tuple[int, int]],
              touching_now: set[tuple[int, int]]) -> int:
        """Count swept hits, for shapes faster than ``swept_speed``, that end the step clear of the obstacle.

        ``candidates`` and ``bound`` are the end-of-step lower bounds (rows: moving shapes), searched to ``within``
        (:meth:`NearestSearch.lower_bounds`). No point of a shape moved farther than its ``travel`` during the step,
        so the bound less the travel bounds the sweep. A pair in ``touching_before`` (in contact at the last check)
        that ends clear left its contact: the sweep hits it at its start, which is no tunneling; one in
        ``touching_now`` (the contacts of this check) is the end-of-step check's to report.
        """
        search = self.search
        model = search.model
        now = (model.position, model.rotation)  # sync replaces these arrays, never writes into them
        previous, self.previous = self.previous, now
        if previous is None or not search.obstacles or not np.isfinite(self.swept_speed):
            return 0
        moving = search.moving
        travel = shape_travel(now[0], now[1], previous[0], previous[1], self._radii, moving)
        rows = np.flatnonzero(travel > self.swept_speed * self.dt)
        if rows.size == 0:
            return 0
        travel = travel[rows]
        tol = search.contact_tolerance
        needed, full = float(travel.max()) + tol, max(search.clearance_range, tol)
        if len(candidates) < len(search.obstacles) and within < min(needed, full):
            # obstacles left out of a narrow search may be in the way: search as far as the sweeps reach (the whole
            # range beyond it), which keeps every pair whose bound less the travel is within the tolerance
            candidates, bound = search.lower_bounds(within=needed if needed <= search.clearance_range else full)
        if len(candidates) < len(search.obstacles) and needed > search.clearance_range:
            # obstacles left out of the end-of-step bounds may be in the way: bound the whole sweeps instead
            grown = np.zeros(len(moving))
            grown[rows] = travel
            candidates, bound = search.lower_bounds(grow=grown)
            reach = bound[rows]
        else:
            reach = bound[rows] - travel[:, None]
        near = reach <= tol
        if not near.any():
            return 0
        # No point of a shape leaves the cones of radius travel * t about its start and travel * (1 - t) about its
        # end, so the sweep stays farther from an obstacle than (start bound + end bound - travel) / 2: only pairs
        # whose bounds at both ends leave that within the tolerance are swept (an approach that ends clear is not).
        start_centres = model.ball_centres_at(previous[0], previous[1])[moving[rows]]
        start = search.bounds.signed_distance_to(start_centres, candidates) - search.slack_radii[rows]
        near &= start + reach <= 2.0 * tol
        hits = 0
        for row in np.flatnonzero(near.any(axis=1)):
            i = int(moving[rows[row]])
            # leaving a contact, or ending in one, is no tunneling: the end-of-step check reports that
            obstacles = [j for j in candidates[near[row]].tolist()
                         if (i, j) not in touching_before and (i, j) not in touching_now]
            if not obstacles:
                continue
            motion = ScrewMotion(previous[1][i], previous[0][i], now[1][i], now[0][i])
            reach_i = tol + model.padding[i]
            for j in self._ball_sweep_survivors(i, motion, obstacles, reach_i):
                if time_of_impact(self._sweepers[i], self._radii[i], motion, search.obstacles[j], reach_i) is not None:
                    hits += 1
        return hits

    def _ball_sweep_survivors(self, shape: int, motion: ScrewMotion, obstacles: list[int], reach: float) -> list[int]:
        """The ``obstacles`` that the enclosing ball of ``shape`` may come within ``reach`` of on ``motion``: its
        centre's exact distance to each at :data:`BALL_SAMPLES` times, and between two samples the cones of the path
        length between them (half of it beyond the mean of the two distances). The rest need no sweep."""
        offset = self._ball_offsets[shape]
        centres = motion.path(offset, BALL_SAMPLES)
        gap = self.search.bounds.signed_distance_to(centres, np.array(obstacles)) - (
            self.search.model.ball_radius[shape] + BOUND_SLACK)
        segment = motion.travel(float(np.linalg.norm(offset))) / (BALL_SAMPLES - 1)
        lowest = (0.5 * (gap[:-1] + gap[1:] - segment)).min(axis=0)
        return [j for j, d in zip(obstacles, lowest.tolist()) if d <= reach]
