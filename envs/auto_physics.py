"""``physics="auto"``: the physics rate and solver iterations a scene needs, chosen from the scene at reset.

Bullet's sequential-impulse solver carries an impulse across one contact per iteration, so what it needs grows with
the movable bodies resting on one another: how many stand in one column, and how much heavier an upper one is than
the one it rests on. The tiers below are the least-cost settings that hold the hard-case catalogue's bound (1 mm and
1 degree over 30 s) on its stacks and loads (docs/hard-cases.md, "Stacks and mass ratios"); a scene with no movable
body on another keeps the env's own settings, which hold a movable box on the floor and a push into a wall. The
robot needs no finer tick at any speed the envs allow (the tunneling rows of the same catalogue).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from clutter_gym.datatypes import Obstacle

PHYSICS_MODES = ("auto", "fixed")
#: (tallest column of movable bodies, heaviest upper-over-lower mass ratio, physics Hz, solver iterations): the first
#: tier whose column and ratio bounds a scene stays within
TIERS = ((5, 10.0, 240.0, 100), (10, 100.0, 480.0, 200), (10, 1000.0, 960.0, 200))
#: metres: a body whose bottom is this close to another's top, over it, rests on it
RESTING = 1e-3
#: bodies whose neighbours one k-d tree query lists at a time: bounds the lists held at once
_CHUNK = 256


@dataclass(frozen=True)
class PhysicsChoice:
    """The settings an episode runs at, and why.

    Attributes:
        physics_hz: physics ticks per simulated second.
        solver_iterations: constraint solver iterations per tick.
        reason: what in the scene asked for them (or that nothing did).
    """

    physics_hz: float
    solver_iterations: int
    reason: str

    def as_info(self) -> dict[str, object]:
        return {"physics_hz": self.physics_hz, "solver_iterations": self.solver_iterations, "reason": self.reason}


def loads(obstacles: Sequence[Obstacle]) -> tuple[int, float]:
    """(the tallest column of movable bodies resting on one another, counted in bodies; the largest mass of a
    movable body over the mass of a movable body it rests on). A scene without such a pair gives (1, 0) or
    (0, 0).

    A body rests on another when its bottom lies within :data:`RESTING` of the other's top, its bottom is higher
    than the other's bottom, and their footprints' enclosing circles overlap. The second condition only matters
    for bodies :data:`RESTING` thick or thinner (for any thicker one it follows from the first); it makes "rests
    on" point upwards, so two thin bodies at one height rest on neither and there is no cycle. The columns are
    then counted in one pass from the lowest body up, each body's from those under it, and the pairs come from a
    k-d tree, so a scene of thousands of movable bodies costs milliseconds (docs/hard-cases.md).
    """
    movable = [o for o in obstacles if o.movable]
    if len(movable) < 2:
        return len(movable), 0.0
    xy = np.array([o.position for o in movable], dtype=float)
    bottom = np.array([o.z for o in movable], dtype=float)
    top = bottom + np.array([o.size[2] for o in movable], dtype=float)
    radius = np.array([o.radius for o in movable], dtype=float)
    mass = np.array([o.mass for o in movable], dtype=float)
    # A pair is within reach[i] in x and in y, and (z scaled) in height: the scale makes every reach cover at
    # least RESTING in height, and at most twice that. The search is wide by a hair (rounding); the exact test
    # below decides.
    reach = radius + radius.max()
    scale = reach.min() / RESTING
    tree = cKDTree(np.column_stack((xy, top * scale)))
    points = np.column_stack((xy, bottom * scale))
    order = np.argsort(bottom, kind="stable")
    height = np.ones(len(movable), dtype=np.int64)
    ratio = 0.0
    for chunk in np.array_split(order, -(-len(order) // _CHUNK)):
        found = tree.query_ball_point(points[chunk], reach[chunk] * (1.0 + 1e-9), p=np.inf, return_sorted=False)
        for i, near in zip(chunk, found):  # lowest first: every body under i has its column counted already
            j = np.asarray(near, dtype=np.int64)
            j = j[(np.abs(bottom[i] - top[j]) <= RESTING) & (bottom[j] < bottom[i])
                  & (np.hypot(xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1]) < radius[i] + radius[j])]
            if j.size:
                height[i] = 1 + height[j].max()
                ratio = max(ratio, float(mass[i] / mass[j].min()))
    return int(height.max()), ratio


def choose_physics(obstacles: Sequence[Obstacle], physics_hz: float, solver_iterations: int,
                   control_hz: float) -> PhysicsChoice:
    """The settings for a scene of ``obstacles``: the env's own (``physics_hz``, ``solver_iterations``) where no
    movable body rests on another, else the first tier of :data:`TIERS` that holds the scene's column and mass
    ratio, never below the env's own settings, its rate rounded up to a multiple of ``control_hz``."""
    tallest, ratio = loads(obstacles)
    if tallest < 2:
        return PhysicsChoice(physics_hz, solver_iterations, "no movable body rests on another")
    what = f"a column of {tallest} movable bodies, the heaviest {ratio:.3g}x the one below it"
    tier = next(((hz, it) for height, most, hz, it in TIERS if tallest <= height and ratio <= most), None)
    if tier is None:
        hz, it = TIERS[-1][2:]
        what += " (beyond the stacks the settings were measured on)"
    else:
        hz, it = tier
    hz = max(hz, physics_hz)
    return PhysicsChoice(math.ceil(hz / control_hz - 1e-9) * control_hz, max(it, solver_iterations), what)
