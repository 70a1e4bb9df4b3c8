"""The Franka Emika Panda (pybullet_data ``franka_panda/panda.urdf``), fixed base, fingers held half open: its
constants and its :class:`ArmModel`. The class that drives it, and any other arm, is ``robots/arm.py``'s ``Arm``."""

from __future__ import annotations

import math

import numpy as np

from clutter_gym.robots.arm import Arm, ArmConfig
from clutter_gym.robots.arm_model import ArmModel
from clutter_gym.sim import pybullet_data_file

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
FINGER_OPENING = 0.02  # metres per finger: half open, the fingers never move
EE_LINK = "panda_grasptarget"  # between the fingertips, 0.105 m along the hand's z axis
#: Links read every step: every link with collision geometry, and the end effector.
TRACKED_LINKS = (*(f"panda_link{i}" for i in range(1, 8)), "panda_hand", "panda_leftfinger", "panda_rightfinger",
                 EE_LINK)
#: Row of the end-effector link in the state's tracked links.
EE_ROW = TRACKED_LINKS.index(EE_LINK)
SHOULDER = np.array([0.0, 0.0, 0.333])  # joint 2's axis above the base, metres
REACH_RADIUS = 0.8  # metres from the shoulder that the hand reaches: ClutterReach draws targets within it
HAND_RADIUS = 0.08  # metres about the end effector that take in the fingers and most of the hand
#: Joint positions of the "ready" pose (hand 0.49 m above the base, pointing down), rad.
READY = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)
LOWER = np.array([-2.9671, -1.8326, -2.9671, -3.1416, -2.9671, -0.0873, -2.9671])
UPPER = np.array([2.9671, 1.8326, 2.9671, 0.0, 2.9671, 3.8223, 2.9671])
SPEED_LIMIT = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])  # URDF velocity limits, rad/s
EFFORT_LIMIT = np.array([87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0])  # URDF effort limits, N m

def panda_model() -> ArmModel:
    """The Panda every ClutterReach result so far was measured with."""
    return ArmModel(
        name="panda", urdf=pybullet_data_file("franka_panda/panda.urdf"), base_link="panda_link0",
        arm_joints=ARM_JOINTS, finger_joints=FINGER_JOINTS, finger_opening=FINGER_OPENING, ee_link=EE_LINK,
        tracked_links=TRACKED_LINKS, ready=READY, lower=LOWER, upper=UPPER, speed_limit=SPEED_LIMIT,
        effort_limit=EFFORT_LIMIT, shoulder=SHOULDER.copy(), reach=REACH_RADIUS, hand_radius=HAND_RADIUS,
        finger_range=(0.0, 0.04),
    )


#: The Panda's control settings are any arm's.
PandaConfig = ArmConfig


class PandaArm(Arm):
    """The Panda, driven as every arm is (``robots/arm.py``)."""

    def __init__(self, config: ArmConfig | None = None, control_dt: float = 0.05) -> None:
        super().__init__(panda_model(), config, control_dt)
