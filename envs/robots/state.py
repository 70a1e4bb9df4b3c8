"""Ground-truth robot state handed from the robot to sensors, collision and tasks (plain data)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clutter_gym.sim import LinkStates


@dataclass(frozen=True, slots=True)
class RobotState:
    """World-frame state of a robot after a physics step.

    Attributes:
        position: (3,) origin of the URDF base frame, metres.
        quaternion: (4,) base orientation (x, y, z, w).
        rotation: (3, 3) base orientation as a matrix (columns are the base axes in world coordinates).
        linear_velocity: velocity of the base centre of mass (vx, vy, vz), m/s.
        angular_velocity: base angular velocity (wx, wy, wz), rad/s.
        links: poses and velocities of the robot's tracked links (sensor mounts, collision links).
        link_names: names of the rows of ``links``.
        link_ids: pybullet link indices of the rows of ``links``.
        body: pybullet body id of the robot.
    """

    position: np.ndarray
    quaternion: np.ndarray
    rotation: np.ndarray
    linear_velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]
    links: LinkStates
    link_names: tuple[str, ...]
    link_ids: tuple[int, ...]
    body: int

    @property
    def yaw(self) -> float:
        """Heading of the base x axis about +z, radians in (-pi, pi]."""
        return math.atan2(self.rotation[1, 0], self.rotation[0, 0])

    def link(self, name: str) -> int:
        """Row of ``links`` that holds link ``name``."""
        return self.link_names.index(name)
