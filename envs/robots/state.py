"""Ground-truth robot state handed from the robot to sensors, collision and tasks (plain data)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clutter_gym.sim import LinkStates


@dataclass(frozen=True)
class RobotState:
    """World-frame state of a robot after a physics step.

    Attributes:
        position: (3,) origin of the URDF base frame, metres.
        quaternion: (4,) base orientation (x, y, z, w).
        rotation: (3, 3) base orientation as a matrix (columns are the base axes in world coordinates).
        linear_velocity: (3,) velocity of the base centre of mass, m/s.
        angular_velocity: (3,) base angular velocity, rad/s.
        links: poses and velocities of the robot's tracked links (sensor mounts, collision links).
        link_names: names of the rows of ``links``.
    """

    position: np.ndarray
    quaternion: np.ndarray
    rotation: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray
    links: LinkStates
    link_names: tuple[str, ...]

    @property
    def yaw(self) -> float:
        """Heading of the base x axis about +z, radians in (-pi, pi]."""
        return float(np.arctan2(self.rotation[1, 0], self.rotation[0, 0]))

    def link(self, name: str) -> int:
        """Row of ``links`` that holds link ``name``."""
        return self.link_names.index(name)
