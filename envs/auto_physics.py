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

from clutter_gym.datatypes import Obstacle

PHYSICS_MODES = ("auto", "fixed")
#: (tallest column of movable bodies, heaviest upper-over-lower mass ratio, physics Hz, solver iterations): the first
#: tier whose column and ratio bounds a scene stays within
TIERS = ((5, 10.0, 240.0, 100), (10, 100.0, 480.0, 200), (10, 1000.0, 960.0, 200))
#: metres: a body whose bottom is this close to another's top, over it, rests on it
RESTING = 1e-3


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


def _rests_on(upper: Obstacle, lower: Obstacle) -> bool:
    """``upper``'s bottom lies on ``lower``'s top and their footprints' enclosing circles overlap."""
    top = lower.z + lower.size[2]
    near = math.dist(upper.position, lower.position) < upper.radius + lower.radius
    return abs(upper.z - top) <= RESTING and near


def loads(obstacles: Sequence[Obstacle]) -> tuple[int, float]:
    """(the tallest column of movable bodies resting on one another, counted in bodies; the largest mass of a
    movable body over the mass of a movable body it rests on). A scene without such a pair gives (1, 0) or
    (0, 0)."""
    movable = [o for o in obstacles if o.movable]
    below: dict[int, list[int]] = {i: [j for j, lower in enumerate(movable) if j != i and _rests_on(o, lower)]
                                   for i, o in enumerate(movable)}
    ratio = max((movable[i].mass / movable[j].mass for i, under in below.items() for j in under), default=0.0)
    height: dict[int, int] = {}

    def column(i: int) -> int:  # a body rests only on lower ones: the recursion ends
        if i not in height:
            height[i] = 1 + max((column(j) for j in below[i]), default=0)
        return height[i]

    tallest = max((column(i) for i in range(len(movable))), default=0)
    return tallest, ratio


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
