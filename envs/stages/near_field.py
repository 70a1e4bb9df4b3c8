"""The near field as a stage: in a large scene (``worlds/near_field.py``) only the obstacles near the robot are
bodies, and after every collision check the arena is told where the robot can be in the next step. Active only in
an episode where the arena engages it."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clutter_gym.collision import CollisionChecker
from clutter_gym.datatypes import Obstacle, RobotState
from clutter_gym.interfaces import Arena
from clutter_gym.stages.base import Stage

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv


class NearField(Stage):
    """Makes every obstacle the robot could touch in the next step a body (see :meth:`checked`)."""

    def bind(self, env: ClutterEnv) -> None:
        self._arena: Arena[Any] = env.arena
        self._checker: CollisionChecker = env.checker
        self._dt = 1.0 / env.control_hz

    def episode_start(self, obstacles: Sequence[Obstacle], bodies: Sequence[int], rng: np.random.Generator) -> bool:
        return self._arena.near_field_engaged

    def checked(self, state: RobotState) -> None:
        """Those within the ball of the robot's shapes (synced by the last check) grown by twice the distance its
        fastest point covers in a step at the speeds of ``state``."""
        centre, reach = self._checker.model.bounding_ball()
        linear = np.vstack((state.linear_velocity, state.links.linear_velocity))
        angular = np.vstack((state.angular_velocity, state.links.angular_velocity))
        speed = math.sqrt(float((linear * linear).sum(axis=1).max()))
        speed += math.sqrt(float((angular * angular).sum(axis=1).max())) * reach
        bodies = self._arena.follow(centre, reach + 2.0 * speed * self._dt)
        if bodies is not None:
            self._checker.set_obstacle_bodies(bodies)
