"""The state read of a robot whose base moves freely: the base and its tracked links from two batched reads."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from clutter_gym.datatypes import RobotState
from clutter_gym.sim import Sim


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
