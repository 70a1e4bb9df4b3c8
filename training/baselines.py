"""Scripted baselines: reference behaviour to compare learned policies with, and the demo's driver."""

from __future__ import annotations

import math
from collections.abc import Mapping

import gymnasium as gym
import numpy as np


class PotentialFieldNavigator:
    """Goal attraction plus LIDAR repulsion (Khatib-style potential field) for ClutterNav.

    The heading is the sum of a unit vector towards the goal and, for every beam closer than ``influence``
    metres, a push away from it weighted by ``1/r - 1/influence``. Angular command = ``turn_gain`` x heading
    error; forward command shrinks with the heading error and with free space ahead. It gets stuck in local
    minima (U-shaped clutter) by design: it is a baseline, not a planner.

    Given ``goal_key="subgoal"`` (an env made with ``subgoal_lookahead > 0``) it steers for the waypoint on the
    shortest path over the known layout instead: a global planner with this field as its local controller, the
    map-based reference a learned policy can be compared with.

    Args:
        lidar_angles: beam angles in the robot frame, radians (None: goal seeking only).
        lidar_range: metres, to undo the observation's normalisation.
        influence: distance below which obstacles repel, metres.
        repulsion: weight of the repulsive sum relative to the unit goal vector.
        turn_gain: angular command per radian of heading error.
        goal_key: the observation entry to steer for, ``"goal"`` or ``"subgoal"``.
    """

    def __init__(
        self,
        lidar_angles: np.ndarray | None,
        lidar_range: float,
        influence: float = 0.5,
        repulsion: float = 0.1,
        turn_gain: float = 1.5,
        goal_key: str = "goal",
    ) -> None:
        if goal_key not in ("goal", "subgoal"):
            raise ValueError(f"goal_key must be 'goal' or 'subgoal', got {goal_key!r}")
        self.angles = None if lidar_angles is None else np.asarray(lidar_angles, dtype=float)
        self.lidar_range = lidar_range
        self.influence, self.repulsion, self.turn_gain = influence, repulsion, turn_gain
        self.goal_key = goal_key

    @classmethod
    def for_env(cls, env: gym.Env, goal_key: str = "goal") -> PotentialFieldNavigator:
        """Configured from a ClutterNav env's LIDAR (or goal seeking only when it has none).

        Raises:
            ValueError: ``goal_key`` is not an entry of the env's observations.
        """
        if goal_key not in env.observation_space.spaces:
            raise ValueError(f"the env has no {goal_key!r} observation"
                             + (" (make it with subgoal_lookahead > 0)" if goal_key == "subgoal" else ""))
        lidar = next((s for s in env.unwrapped.sensors if s.name == "lidar"), None)
        if lidar is None:
            return cls(None, 1.0, goal_key=goal_key)
        return cls(lidar.config.angles, lidar.config.max_range, goal_key=goal_key)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        _, sin_b, cos_b = (float(v) for v in obs[self.goal_key])
        heading = np.array([cos_b, sin_b])
        ahead = 1.0
        if self.angles is not None and "lidar" in obs:
            ranges = np.asarray(obs["lidar"], dtype=float) * self.lidar_range
            close = ranges < self.influence
            push = (1.0 / np.maximum(ranges[close], 1e-3) - 1.0 / self.influence)
            angles = self.angles[close]
            heading -= self.repulsion * np.array([push @ np.cos(angles), push @ np.sin(angles)])
            front = np.abs(self.angles) < math.radians(30)
            ahead = float(np.clip((ranges[front].min() - 0.2) / 0.6, 0.0, 1.0)) if front.any() else 1.0
        error = math.atan2(heading[1], heading[0])
        angular = float(np.clip(self.turn_gain * error, -1.0, 1.0))
        linear = float(np.clip(math.cos(error), 0.0, 1.0)) * max(ahead, 0.15)
        return np.array([linear, angular], dtype=np.float32)


class StraightLineReacher:
    """Scripted IK for ClutterReach: the end effector heads straight for the target, as fast as allowed.

    With ``control="ee_position"`` each action is the displacement towards the target, in units of
    ``max_ee_step`` and clipped to [-1, 1]; pybullet's IK turns it into joint targets. It ignores the clutter
    entirely, so it measures how often the straight line is free: a learned policy should beat it on contacts.
    """

    def __init__(self, max_ee_step: float) -> None:
        self.max_ee_step = max_ee_step

    @classmethod
    def for_env(cls, env: gym.Env) -> StraightLineReacher:
        """Configured from a ClutterReach env made with ``control="ee_position"``.

        Raises:
            ValueError: the env has another action space (joint-velocity control).
        """
        config = getattr(env.unwrapped.robot, "config", None)
        if getattr(config, "control", None) != "ee_position":
            raise ValueError("StraightLineReacher needs a ClutterReach env made with control='ee_position'")
        return cls(config.max_ee_step)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        offset = np.asarray(obs["target"], dtype=float) - np.asarray(obs["ee_position"], dtype=float)
        return np.clip(offset / self.max_ee_step, -1.0, 1.0).astype(np.float32)
