"""Movable obstacles as a stage: after the physics, the collision checker follows what it pushed. Active only in
an episode whose scene has movable obstacles."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from clutter_gym.collision import CollisionChecker
from clutter_gym.datatypes import Obstacle
from clutter_gym.sim import Sim
from clutter_gym.stages.base import Stage

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv


class Movables(Stage):
    """The episode's movable obstacles: their scene indices and bodies (:attr:`bodies`)."""

    def __init__(self) -> None:
        self.indices = np.zeros(0, dtype=int)
        self.bodies: list[int] = []

    def bind(self, env: ClutterEnv) -> None:
        self._sim: Sim = env.sim
        self._checker: CollisionChecker = env.checker

    def episode_start(self, obstacles: Sequence[Obstacle], bodies: Sequence[int], rng: np.random.Generator) -> bool:
        movable = [i for i, o in enumerate(obstacles) if o.movable]
        self.indices, self.bodies = np.array(movable, dtype=int), [bodies[i] for i in movable]
        return bool(movable)

    def physics_done(self) -> None:
        self._checker.move_obstacles(self.indices, *self._sim.obstacles.body_poses(self.bodies))
