"""``dynamics=`` of an env: which part moves the robot (:mod:`clutter_gym.dynamics.base`), chosen at make time.

- ``"physics"``: pybullet's full simulation, always.
- ``"reduced"``: the robot's reduced model while nothing is within a step's reach, full physics otherwise
  (:class:`~clutter_gym.dynamics.reduced_drive.ReducedDrive` for a differential drive,
  :class:`~clutter_gym.dynamics.reduced_flight.ReducedFlight` for a multirotor,
  :class:`~clutter_gym.dynamics.reduced_arm.ReducedArm` for a fixed-base arm); a robot without a reduced model is
  refused.
- ``"auto"``: the reduced model where one exists and its error against the full-physics robot is within its bound
  (:data:`AUTO_ERROR_BOUND`, :data:`AUTO_FLIGHT_BOUND`, :data:`AUTO_ARM_BOUND`); full physics otherwise. The reset's
  ``info["dynamics"]`` says which and why.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import partial
from typing import Any

from clutter_gym.dynamics.arm_check import arm_gap
from clutter_gym.dynamics.base import Dynamics, DynamicsFactory, FullPhysics
from clutter_gym.dynamics.drive_fit import fit_drive
from clutter_gym.dynamics.flight_check import flight_gap
from clutter_gym.dynamics.reduced_arm import ReducedArm
from clutter_gym.dynamics.reduced_drive import ReducedDrive
from clutter_gym.dynamics.reduced_flight import ReducedFlight
from clutter_gym.robots.arm import Arm
from clutter_gym.robots.diffdrive import DiffDriveRobot
from clutter_gym.robots.multirotor import Multirotor

DYNAMICS_MODES = ("physics", "reduced", "auto")
#: the largest error of a reduced drive model that ``"auto"`` takes: the root-mean-square speed error over its fit's
#: probe, as a share of the commanded maxima (docs/speed-vs-error.md, "Reduced dynamics")
AUTO_ERROR_BOUND = 0.10
#: m, the largest distance between pybullet's flight of a multirotor's probe and its reduced model's that ``"auto"``
#: takes (:mod:`~clutter_gym.dynamics.flight_check`; the two run the same equations, so they agree to rounding)
AUTO_FLIGHT_BOUND = 1e-3
#: m, the largest distance between the end effector as pybullet drives an arm's probe and as its reduced model does
#: that ``"auto"`` takes: under half of ClutterReach's default clearance margin and success radius (0.05 m)
AUTO_ARM_BOUND = 0.02


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


def flight_dynamics(mode: str, robot: Multirotor, radius: float, physics_hz: float, solver_iterations: int,
                    control_hz: float, contact_tolerance: float) -> DynamicsFactory:
    """The dynamics part ``mode`` gives a multirotor whose collision shapes reach ``radius`` metres from its centre of
    mass: a factory of it from the env's Sim and robot. ``"auto"`` takes the reduced model where it flies
    :mod:`~clutter_gym.dynamics.flight_check`'s probe within :data:`AUTO_FLIGHT_BOUND` of pybullet."""
    return _probed(mode, robot.name, "its centre of mass",
                   lambda: flight_gap(robot.model, robot.config, physics_hz, solver_iterations, control_hz),
                   AUTO_FLIGHT_BOUND, partial(ReducedFlight, radius=radius, contact_tolerance=contact_tolerance))


def arm_dynamics(mode: str, robot: Arm, radii: Mapping[str, float], physics_hz: float, solver_iterations: int,
                 control_hz: float, contact_tolerance: float) -> DynamicsFactory:
    """The dynamics part ``mode`` gives a fixed-base arm whose links' collision shapes reach ``radii`` (metres, by
    link) from their frames: a factory of it from the env's Sim and robot. ``"auto"`` takes the reduced model where
    it drives :mod:`~clutter_gym.dynamics.arm_check`'s probe within :data:`AUTO_ARM_BOUND` of pybullet."""
    return _probed(mode, robot.name, "its hand", lambda: arm_gap(robot.model, robot.config, physics_hz,
                                                                 solver_iterations, control_hz),
                   AUTO_ARM_BOUND, partial(ReducedArm, radii=radii, contact_tolerance=contact_tolerance))


def _probed(mode: str, name: str, what: str, gap: Callable[[], float], bound: float,
            reduced: Callable[..., Dynamics]) -> DynamicsFactory:
    """The part ``mode`` gives a robot whose reduced model is checked on a probe: ``gap()`` is how far (m) ``what``
    ends from pybullet's over it, measured only for ``"auto"``."""
    check_dynamics_mode(mode)
    if mode == "physics":
        return partial(FullPhysics, reason="the env's settings (dynamics='physics')")
    if mode == "reduced":
        return partial(reduced, reason="the env's settings (dynamics='reduced')")
    off = gap()
    if off > bound:
        return partial(FullPhysics, reason=f"the reduced model of {name!r} moves {what} {off:.2g} m from pybullet's "
                                           f"over its probe, over the {bound:g} m bound (dynamics='auto')")
    return partial(reduced, reason=f"the reduced model of {name!r} keeps {what} within {off:.2g} m of pybullet's "
                                   f"over its probe (dynamics='auto')")
