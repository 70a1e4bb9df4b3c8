"""Wheel odometry: the pose a differential drive dead-reckons from its wheel encoders, relative to where the
episode started, and the last step's travel.

Each step it reads the wheels' angles (the simulated wheels', so their slip against the floor is in it), counts them
as the encoders do, and integrates the travel of each side, ``d = r_side * delta angle``, into the pose as the arc
they describe: ``ds = (d_right + d_left) / 2`` along it, ``dtheta = (d_right - d_left) / track`` round it, so the
base moves by the chord ``ds * sin(dtheta / 2) / (dtheta / 2)`` at the mean heading (exact for constant wheel
speeds over a step; the midpoint rule is its small-angle limit). With several wheels a side
(a skid-steer base), a side's angle is their mean. The radii and the track are the ones the odometry believes in,
the robot's own times this episode's scales (:mod:`clutter_gym.noise.odometry`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import RobotState
from clutter_gym.noise.odometry import OdometryNoise, encoder_angle, start_odometry_episode
from clutter_gym.sensors.suite import Observed
from clutter_gym.sim import Sim


class WheelOdometry:
    """Odometry of a wheeled base (a :class:`~clutter_gym.robots.DiffDriveRobot`).

    Observation ``odometry``: (x, y, sin yaw, cos yaw, ds, dyaw), float32: the pose in metres in the frame of the
    episode's start (x forward, y left), and the last step's travel in metres and radians. A reading is
    (x, y, yaw, ds, dyaw).

    Raises:
        ValueError: the robot is not a wheeled base.
    """

    name = "odometry"
    read_every_step = True  # it integrates every step, also while its output is held
    renders = False
    needs_bodies = False
    spaces = {"odometry": spaces.Box(-np.inf, np.inf, (6,), np.float32)}
    observation = (Observed(
        "odometry", "(6,)", "x, y, sin(yaw), cos(yaw) since the episode's start, then the last step's travel and turn",
        "m, -, -, m, rad; the start's frame (x forward, y left)", "unbounded"),)

    def __init__(self, robot: Any, noise: OdometryNoise | None = None) -> None:
        if not hasattr(getattr(robot, "base", None), "left_wheels"):
            raise ValueError(f"the odometry sensor reads a wheeled base's wheels; {type(robot).__name__} has none")
        self.robot, self.noise = robot, noise or OdometryNoise()
        self._n_left = len(robot.base.left_wheels)

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        left, right, track = start_odometry_episode(rng, self.noise)
        config = self.robot.config
        self._radii = (config.wheel_radius * left, config.wheel_radius * right)
        self._track = config.wheel_separation * track
        self._angles = self._sides(sim, state)
        self._pose = [0.0, 0.0, 0.0]

    def _sides(self, sim: Sim, state: RobotState) -> tuple[float, float]:
        """The left and right sides' angles as the encoders count them."""
        angles, _ = sim.actuation.joint_states(state.body, self.robot.wheel_joints)
        ticks = self.noise.ticks_per_rev
        return (encoder_angle(float(np.mean(angles[:self._n_left])), ticks),
                encoder_angle(float(np.mean(angles[self._n_left:])), ticks))

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> np.ndarray:
        left, right = self._sides(sim, state)
        d_left = (left - self._angles[0]) * self._radii[0]
        d_right = (right - self._angles[1]) * self._radii[1]
        self._angles = (left, right)
        ds, dyaw = 0.5 * (d_right + d_left), (d_right - d_left) / self._track
        x, y, yaw = self._pose
        half = 0.5 * dyaw
        chord = ds * (math.sin(half) / half if abs(half) > 1e-9 else 1.0)
        heading = yaw + half
        self._pose = [x + chord * math.cos(heading), y + chord * math.sin(heading), yaw + dyaw]
        return np.array([*self._pose, ds, dyaw])

    def observe(self, reading: np.ndarray) -> dict[str, np.ndarray]:
        x, y, yaw, ds, dyaw = reading
        return {"odometry": np.array([x, y, math.sin(yaw), math.cos(yaw), ds, dyaw], dtype=np.float32)}

    def info(self, reading: np.ndarray) -> dict[str, Any]:
        return {"odometry_pose": reading[:3].copy()}
