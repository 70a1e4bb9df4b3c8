"""Robots: one module each; a robot loads itself into a Sim, maps actions to motors and reads its state."""

from clutter_gym.datatypes import RobotState
from clutter_gym.robots.arm import Arm, ArmConfig
from clutter_gym.robots.diffdrive import DiffDriveConfig, DiffDriveRobot
from clutter_gym.robots.multirotor import Multirotor, MultirotorConfig
from clutter_gym.robots.panda import PandaArm, PandaConfig
from clutter_gym.robots.quadrotor import Quadrotor, QuadrotorConfig

__all__ = ["Arm", "ArmConfig", "DiffDriveConfig", "DiffDriveRobot", "Multirotor", "MultirotorConfig", "PandaArm",
           "PandaConfig", "Quadrotor", "QuadrotorConfig", "RobotState"]
