"""IMU: specific force and angular rate in the IMU link frame, from the link's velocities.

Specific force is what an accelerometer measures: ``f = R^T (a - g)`` with ``g = (0, 0, -9.81)`` m/s^2, so a
sensor at rest reads ``+9.81`` along its up axis. ``a`` is the finite difference of the link's world velocity
over one control period, i.e. the mean acceleration over the period, which is what an IMU whose output is
averaged to the control rate reports. The angular rate is ``R^T w``. Both saturate at the full-scale range.
Noise (:mod:`clutter_gym.noise.imu`) is generated for that averaged sample: white noise of std ``ND / sqrt(dt)``
and one bias step of ``dt`` per control step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import RobotState
from clutter_gym.noise.imu import ACCEL_RANGE, GYRO_RANGE, ImuEpisode, ImuNoise, apply_imu_noise, start_imu_episode
from clutter_gym.sensors.suite import Observed
from clutter_gym.sim import GRAVITY, Sim


@dataclass(frozen=True)
class ImuConfig:
    """Attributes:
        dt: sample period in seconds (the env's control period).
        gravity: m/s^2, the same value the simulation uses.
        accel_range: accelerometer full scale, m/s^2 (16 g, a common MEMS setting).
        gyro_range: gyroscope full scale, rad/s (2000 deg/s).
        link: URDF link the IMU is mounted on.
    """

    dt: float
    gravity: float = GRAVITY
    accel_range: float = ACCEL_RANGE
    gyro_range: float = GYRO_RANGE
    link: str = "imu_link"


class Imu:
    """Observation ``imu``: (f_x, f_y, f_z) in m/s^2 then (w_x, w_y, w_z) in rad/s, IMU link frame, clipped at
    full scale."""

    name = "imu"
    read_every_step = True  # the finite difference needs every control step, even while the output is held
    renders = False
    needs_bodies = False
    observation = (Observed(
        "imu", "(6,)", "specific force (f_x, f_y, f_z), then angular rate (w_x, w_y, w_z), clipped at full scale; "
        "+9.81 m/s^2 on z at rest", "m/s^2, rad/s; its link's axes", "+-156.9 (16 g), +-34.9 (2000 deg/s)"),)

    def __init__(self, config: ImuConfig, noise: ImuNoise | None = None) -> None:
        self.config = c = config
        self.noise = noise or ImuNoise()
        self._bound = np.array([c.accel_range] * 3 + [c.gyro_range] * 3, dtype=np.float32)
        self.spaces = {"imu": spaces.Box(-self._bound, self._bound, dtype=np.float32)}
        self._gravity = np.array([0.0, 0.0, -c.gravity])
        self._rate = 1.0 / c.dt
        self._previous_velocity = np.zeros(3)
        self._episode = ImuEpisode()

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        """Start the finite difference from the current velocity (the first sample reads zero acceleration) and
        draw this episode's turn-on bias, scale and misalignment."""
        self._previous_velocity = state.links.linear_velocity[state.link(self.config.link)].copy()
        self._episode = start_imu_episode(rng, self.noise)

    def read_clean(self, state: RobotState) -> np.ndarray:
        """Exact specific force and angular rate (6,), IMU frame, before saturation."""
        row = state.link(self.config.link)
        velocity = state.links.linear_velocity[row].copy()
        world = np.empty((2, 3))
        np.multiply(velocity - self._previous_velocity, self._rate, out=world[0])
        world[0] -= self._gravity
        world[1] = state.links.angular_velocity[row]
        self._previous_velocity = velocity
        return (world @ state.links.rotation[row]).ravel()  # rows: R^T (a - g), R^T w

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> np.ndarray:
        clean = self.read_clean(state)
        if self.noise.is_clean:
            return clean
        return apply_imu_noise(clean, rng, self.noise, self._episode, self.config.dt)

    def observe(self, reading: np.ndarray) -> dict[str, np.ndarray]:
        return {"imu": np.minimum(np.maximum(reading, -self._bound), self._bound).astype(np.float32)}

    def info(self, reading: np.ndarray) -> dict[str, Any]:
        return {}
