"""ClutterReach-v1's hand controller: a policy picks where the hand goes next and how it is pitched, and the
controller turns that into the env's joint-velocity action.

A student imitating a planner's joint velocities has to learn, joint by joint, reconfigurations that the planner
chose differently on every layout; it learnt the reaches above the table and none into the shelf
(docs/learning.md, "The ClutterReach student"). Through this controller the policy's action is four numbers: the
hand's displacement over the next step (x, y, z in world axes, up to :data:`HAND_STEP` metres each) and its pitch,
from level (-1) to pointing down (+1), on the family of orientations of :mod:`clutter_gym.planning.hand_pose` (the
approach axis in the vertical plane through the target, the fingers' opening level). One damped-least-squares
step on the arm's forward kinematics gives the joints' change, scaled to the joints' speed; the residual
machinery (``residual_space="waypoint"``) calls :meth:`HandController.toward`.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from clutter_gym.planning.hand_pose import HandPose, hand_axis
from clutter_gym.robots.arm_model import ArmModel

#: Metres the hand moves in one control step at an action entry of 1 (0.4 m/s at ClutterReach-v1's 20 Hz).
HAND_STEP = 0.02
#: The pitch an action of 0 asks for, and how far its -1..1 reaches either way: level to pointing down, radians.
PITCH_MID = PITCH_SCALE = math.pi / 4


class HandController:
    """Joint-velocity actions that move an arm's hand by a displacement, at a pitch.

    Args:
        arm: the arm.
        joint_step: each joint's largest change in one control step at an action of 1, radians (n_joints,).
    """

    #: What the policy's action entries -1..1 span: metres along x, y and z, and radians of pitch about its middle.
    waypoint_scales = (HAND_STEP, HAND_STEP, HAND_STEP, PITCH_SCALE)

    def __init__(self, arm: ArmModel, joint_step: np.ndarray) -> None:
        self.hand = HandPose(arm)
        self.rest = np.asarray(arm.ready, dtype=float)
        self.joint_step = np.asarray(joint_step, dtype=float)

    @classmethod
    def for_env(cls, env: gym.Env) -> HandController:
        """The controller of a ClutterReach env's arm, at its joint speeds and control period.

        Raises:
            ValueError: the env is not under joint-velocity control.
        """
        robot: Any = getattr(env.unwrapped, "robot")
        if getattr(robot.config, "control", None) != "joint_velocity":
            raise ValueError("the hand controller needs a ClutterReach env made with control='joint_velocity'")
        return cls(robot.model, robot.speed * robot.control_dt)

    def toward(self, obs: dict[str, np.ndarray], dx: float, dy: float, dz: float, pitch: float) -> np.ndarray:
        """The joint-velocity action (float32, within [-1, 1]) moving the hand by (dx, dy, dz) metres, pitched
        ``PITCH_MID + pitch`` radians below level, from the observation's joints and target."""
        q = np.asarray(obs["joint_position"], dtype=float)
        target = np.asarray(obs["target"], dtype=float)
        rest = self.rest.copy()
        rest[0] = math.atan2(target[1], target[0])  # the ready posture, turned to face the target
        change = self.hand.step(q, np.array([dx, dy, dz]), hand_axis(target, PITCH_MID + pitch), rest=rest,
                                relative=True)[0]
        action = change / self.joint_step
        return (action / max(1.0, float(np.abs(action).max()))).astype(np.float32)
