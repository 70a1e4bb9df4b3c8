"""ClutterFly-v1's flyer steered by a LIDAR potential field: sensor-only local obstacle avoidance in 3-D.

The velocity it flies is a pull along a target direction (towards the goal, or a waypoint direction a policy picks)
plus a push away from every LIDAR return closer than ``influence`` (Khatib's field, as ClutterNav-v1's
:class:`~clutter_gym.training.baselines.PotentialFieldNavigator` on its 2-D scan), slowed where the returns ahead
are close, and the :class:`~clutter_gym.training.baselines.CascadedFlyer`'s inner loops fly it, turning the nose
(and with it the LIDAR) towards the way it flies. Like every potential field it stops in front of obstacles whose
way round it cannot see; a student that picks its waypoint (docs/learning.md) supplies that choice.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import gymnasium as gym
import numpy as np

from clutter_gym.training.baselines import CascadedFlyer, _capped
from clutter_gym.training.residual import FACING_GAIN


class FieldFlyer:
    """See the module docstring.

    Args:
        flyer: the cascaded flyer whose inner loops fly the field's velocity (its ``max_speed`` caps it).
        directions: (beams, 3) the LIDAR's beam directions in the body frame, in the observation's order.
        max_range: the LIDAR's range, metres (a reading of 1 is no return).
        influence: metres within which a return pushes.
        repulsion: the push's weight, m/s per (1/r - 1/influence).
    """

    #: what the action entries -1..1 of a policy picking this field's waypoint span: azimuth, elevation, radians
    waypoint_scales = (math.pi, math.pi / 2)

    def __init__(self, flyer: CascadedFlyer, directions: np.ndarray, max_range: float, influence: float = 0.4,
                 repulsion: float = 0.05) -> None:
        self.flyer, self.directions, self.max_range = flyer, np.asarray(directions, dtype=float), max_range
        self.influence, self.repulsion = influence, repulsion
        horizontal = np.hypot(self.directions[:, 0], self.directions[:, 1])
        self._front = (self.directions[:, 0] > math.cos(math.radians(30)) * np.linalg.norm(self.directions, axis=1)) \
            & (horizontal > 0)

    @classmethod
    def for_env(cls, env: gym.Env, **field: float) -> FieldFlyer:
        """Configured from a ClutterFly env's LIDAR, on the nominal quadrotor's flyer turning its nose.

        Raises:
            ValueError: the env has no LIDAR.
        """
        lidar = next((s for s in getattr(env.unwrapped, "sensors", ()) if s.name == "lidar"), None)
        if lidar is None:
            raise ValueError("the field flyer needs a ClutterFly env with 'lidar' in sensors")
        c = lidar.config
        azimuth = np.broadcast_to(c.angles, c.shape).reshape(-1)
        elevation = np.repeat(c.elevations, c.n_rays)
        directions = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                               np.sin(elevation)], axis=1)
        return cls(CascadedFlyer.nominal("goal", yaw_gain=FACING_GAIN), directions, c.max_range, **field)

    def velocity(self, obs: Mapping[str, np.ndarray], direction: np.ndarray) -> np.ndarray:
        """The field's velocity (m/s, body frame) for a pull along ``direction`` (body frame, any length)."""
        pull = np.asarray(direction, dtype=float)
        pull = self.flyer.max_speed * pull / max(float(np.linalg.norm(pull)), 1e-9)
        ranges = np.asarray(obs["lidar"], dtype=float).reshape(-1) * self.max_range
        close = ranges < self.influence
        push = (1.0 / np.maximum(ranges[close], 1e-3) - 1.0 / self.influence)[:, None] * self.directions[close]
        wanted = pull - self.repulsion * push.sum(axis=0)
        ahead = float(np.clip((ranges[self._front].min() - 0.3) / 1.0, 0.15, 1.0)) if self._front.any() else 1.0
        return _capped(wanted, self.flyer.max_speed * ahead)

    def toward(self, obs: Mapping[str, np.ndarray], azimuth: float, elevation: float) -> np.ndarray:
        """The action flying the field with its pull at ``azimuth`` and ``elevation`` (radians, body frame)."""
        direction = np.array([math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                              math.sin(elevation)])
        return self.flyer.track(self.velocity(obs, direction), obs)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        """The action pulled towards the goal: the sensor-only scripted flyer."""
        return self.flyer.track(self.velocity(obs, np.asarray(obs["goal"], dtype=float)[:3]), obs)
