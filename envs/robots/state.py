"""Ground-truth robot state handed from the robot to sensors, collision and tasks (plain data)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from clutter_gym.sim import LinkStates, Sim


@dataclass(frozen=True, slots=True)
class RobotState:
    """World-frame state of a robot after a physics step.

    Attributes:
        position: (3,) origin of the URDF base frame, metres.
        rotation: (3, 3) base orientation (columns are the base axes in world coordinates).
        linear_velocity: velocity of the base centre of mass (vx, vy, vz), m/s.
        angular_velocity: base angular velocity (wx, wy, wz), rad/s.
        links: poses and velocities of the links read every step (the IMU and every collision link).
        link_names: names of the rows of ``links``.
        link_index: pybullet index of every link of the robot by URDF name (-1 for the base); constant. Links merged
            into a rigid base (the quadrotor's) have none: their states are among ``links``.
        body: pybullet body id of the robot.
        joint_position: positions of the robot's actuated joints (rad or m), an arm's; empty for the diffbot.
        joint_velocity: their velocities (rad/s or m/s).
    """

    position: np.ndarray
    rotation: np.ndarray
    linear_velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]
    links: LinkStates
    link_names: tuple[str, ...]
    link_index: Mapping[str, int]
    body: int
    joint_position: np.ndarray = field(default_factory=lambda: np.zeros(0))
    joint_velocity: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def yaw(self) -> float:
        """Heading of the base x axis about +z, radians in (-pi, pi]."""
        return math.atan2(self.rotation[1, 0], self.rotation[0, 0])

    def link(self, name: str) -> int:
        """Row of ``links`` that holds link ``name``."""
        return self.link_names.index(name)


def floating_base_state(sim: Sim, body: int, com_offset: np.ndarray, tracked: list[int],
                        link_names: tuple[str, ...], link_index: Mapping[str, int]) -> RobotState:
    """The state of a robot whose base moves freely (no joint positions), from two batched pybullet reads.

    Args:
        sim: the physics client.
        body: the robot's body id.
        com_offset: the base's centre of mass in the base link frame, metres (pybullet reports base poses there).
        tracked: pybullet indices of the links read every step, in the order of ``link_names``.
        link_names: names of the rows of ``RobotState.links``.
        link_index: pybullet index of every link by URDF name.
    """
    com, rot, lin, ang = sim.base_state(body)
    rot = np.reshape(rot, (3, 3))
    return RobotState(
        position=np.asarray(com) - rot @ com_offset,
        rotation=rot,
        linear_velocity=lin,
        angular_velocity=ang,
        links=sim.link_states(body, tracked),
        link_names=link_names,
        link_index=link_index,
        body=body,
    )
