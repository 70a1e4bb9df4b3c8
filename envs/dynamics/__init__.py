"""What moves the robot through a step: pybullet's full physics, or a reduced model where nothing needs contact
physics (docs/architecture.md, "Dynamics")."""

from clutter_gym.dynamics.base import Dynamics, FullPhysics
from clutter_gym.dynamics.choice import (
                                         DYNAMICS_MODES,
                                         arm_dynamics,
                                         check_dynamics_mode,
                                         flight_dynamics,
                                         ground_dynamics,
)
from clutter_gym.dynamics.drive_fit import DriveFit, fit_drive
from clutter_gym.dynamics.drive_model import DriveParams, drive_ticks
from clutter_gym.dynamics.reduced_arm import ReducedArm
from clutter_gym.dynamics.reduced_drive import ReducedDrive
from clutter_gym.dynamics.reduced_flight import ReducedFlight

__all__ = ["DYNAMICS_MODES", "DriveFit", "DriveParams", "Dynamics", "FullPhysics", "ReducedArm", "ReducedDrive",
           "ReducedFlight", "arm_dynamics", "check_dynamics_mode", "drive_ticks", "fit_drive", "flight_dynamics",
           "ground_dynamics"]
