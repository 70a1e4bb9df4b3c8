"""``dynamics=`` of an env: which part moves the robot (:mod:`clutter_gym.dynamics.base`), chosen at make time.

- ``"physics"``: pybullet's full simulation, always.
- ``"reduced"``: the robot's reduced model while nothing is within a step's reach, full physics otherwise
  (:class:`~clutter_gym.dynamics.reduced_drive.ReducedDrive`); a robot without a reduced model is refused.
- ``"auto"``: the reduced model where one exists and its fit to the full-physics robot is within
  :data:`AUTO_ERROR_BOUND`; full physics otherwise. The reset's ``info["dynamics"]`` says which and why.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from clutter_gym.dynamics.base import DynamicsFactory, FullPhysics
from clutter_gym.dynamics.drive_fit import fit_drive
from clutter_gym.dynamics.reduced_drive import ReducedDrive
from clutter_gym.robots.diffdrive import DiffDriveRobot

DYNAMICS_MODES = ("physics", "reduced", "auto")
#: the largest error of a reduced drive model that ``"auto"`` takes: the root-mean-square speed error over its fit's
#: probe, as a share of the commanded maxima (docs/speed-vs-error.md, "Reduced dynamics")
AUTO_ERROR_BOUND = 0.10


def check_dynamics_mode(dynamics: Any) -> None:
    """Raise at make time for a ``dynamics`` that is not one of :data:`DYNAMICS_MODES`."""
    if not (isinstance(dynamics, str) and dynamics in DYNAMICS_MODES):
        raise ValueError(f"dynamics must be one of {DYNAMICS_MODES}, got {dynamics!r}")


def ground_dynamics(mode: str, robot: Any, physics_hz: float, solver_iterations: int, control_hz: float,
                    contact_tolerance: float) -> DynamicsFactory:
    """The dynamics part ``mode`` gives a ground robot: a factory of it from the env's Sim and robot.

    Raises:
        ValueError: ``mode`` is not one of :data:`DYNAMICS_MODES`, or is ``"reduced"`` for a robot that has no reduced
            model (only a differential drive has one).
    """
    check_dynamics_mode(mode)
    if mode == "physics":
        return partial(FullPhysics, reason="the env's settings (dynamics='physics')")
    if not isinstance(robot, DiffDriveRobot):
        if mode == "reduced":
            raise ValueError(f"dynamics='reduced' needs a differential drive (the reduced model is a unicycle); robot "
                             f"{robot.name!r} is not one: use dynamics='physics' or 'auto'")
        return partial(FullPhysics, reason=f"no reduced model for robot {robot.name!r} (dynamics='auto')")
    fit = fit_drive(robot.base, robot.config, physics_hz, solver_iterations, control_hz)
    if mode == "auto" and fit.error > AUTO_ERROR_BOUND:
        return partial(FullPhysics, reason=f"the reduced model of {robot.name!r} is off by {fit.error:.0%} of its "
                                           f"speeds, over the {AUTO_ERROR_BOUND:.0%} bound (dynamics='auto')")
    reason = ("the env's settings (dynamics='reduced')" if mode == "reduced" else
              f"the reduced model of {robot.name!r} is within {fit.error:.1%} of its speeds (dynamics='auto')")
    return partial(ReducedDrive, fit=fit, control_hz=control_hz, contact_tolerance=contact_tolerance, reason=reason)
