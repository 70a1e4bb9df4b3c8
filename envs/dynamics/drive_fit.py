"""Fit a differential drive's reduced model (:class:`~clutter_gym.dynamics.drive_model.DriveParams`) to the
full-physics robot: drive it on an empty floor through a fixed sequence of commands and fit the model's speeds to
the measured ones by least squares. Done once per base, drive limits and rates in a process (cached).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.dynamics.drive_model import LEFT, RIGHT, STATE_SIZE, DriveParams, drive_ticks
from clutter_gym.robots.diffdrive import DiffDriveConfig, DiffDriveRobot
from clutter_gym.robots.wheeled import WheeledBase
from clutter_gym.sim import Sim

#: s, how long the probe holds each of its commands
HOLD_SECONDS = 0.4
#: the probe's commands (normalised linear, angular), drawn once from a fixed seed: full-scale steps, reversals, turns
#: in place, arcs and stops, the same for every robot
PROBE_COMMANDS = np.random.default_rng(20261128).choice([-1.0, -0.5, 0.0, 0.5, 1.0], size=(20, 2))
#: the motors' torque limit times this in the grip probe: the wheels then spin on the floor, and the base's
#: acceleration is what the floor's friction allows
GRIP_TORQUE_SCALE = 20.0


@dataclass(frozen=True)
class DriveFit:
    """A reduced drive model and how well it reproduces the full-physics robot.

    Attributes:
        params: the fitted model.
        grip: m/s^2, the forward acceleration the floor's friction allows the base (the grip probe's).
        error: the probe's root-mean-square speed error of the model, as a share of the commanded maxima, the worse
            of forward speed and yaw rate.
    """

    params: DriveParams
    grip: float
    error: float


def probe(robot: DiffDriveRobot, physics_hz: float, solver_iterations: int, control_hz: float,
          commands: np.ndarray = PROBE_COMMANDS, hold: float = HOLD_SECONDS) -> tuple[np.ndarray, np.ndarray]:
    """Drive ``robot`` (not loaded anywhere) through ``commands``, each held ``hold`` seconds, on an empty floor.

    Returns:
        (the command of each control step (n, 2), normalised; the forward speed m/s and yaw rate rad/s after it
        (n, 2)).
    """
    with _on_empty_floor(robot, physics_hz, solver_iterations) as sim:
        substeps = int(round(physics_hz / control_hz))
        steps = np.repeat(np.asarray(commands, dtype=np.float64), int(round(hold * control_hz)), axis=0)
        speeds = np.empty_like(steps)
        for i, command in enumerate(steps):
            robot.apply_action(command)
            sim.step(substeps)
            speeds[i] = robot.observe(robot.state())["velocity"][:2]
        return steps, speeds


def simulate(params: DriveParams, commands: np.ndarray, config: DiffDriveConfig, physics_hz: float,
             control_hz: float) -> np.ndarray:
    """The model's (forward speed, yaw rate) after each control step of ``commands`` (normalised), from rest."""
    state = np.zeros(STATE_SIZE)
    array = params.as_array()
    substeps = int(round(physics_hz / control_hz))
    out = np.empty((len(commands), 2))
    for i, (linear, angular) in enumerate(commands):
        left, right = params.sides(linear * config.max_linear_speed, angular * config.max_angular_speed)
        drive_ticks(state, left, right, array, 1.0 / physics_hz, substeps)
        out[i] = params.body(state[LEFT], state[RIGHT])
    return out


@functools.lru_cache(maxsize=16)
def fit_drive(base: WheeledBase, config: DiffDriveConfig, physics_hz: float, solver_iterations: int,
              control_hz: float) -> DriveFit:
    """The reduced model that best reproduces the robot on ``base`` with the drive limits of ``config`` (its probe),
    with its grip and error."""
    commands, measured = probe(DiffDriveRobot(config, base), physics_hz, solver_iterations, control_hz)
    scale = np.array([config.max_linear_speed, config.max_angular_speed])
    track = base.wheel_separation

    def residual(x: np.ndarray) -> np.ndarray:
        model = simulate(DriveParams(x[0], x[1], x[2], x[3], track), commands, config, physics_hz, control_hz)
        return ((model - measured) / scale).ravel()

    # from the URDF's track and from a wide one (a skid-steer base turns as if its sides were further apart)
    fit = min((least_squares(residual, x0=[2.0, 0.02, 0.0, start * track], diff_step=1e-3,
                             bounds=([0.05, 0.0, 0.0, 0.5 * track], [100.0, 1.0, 0.5, 5.0 * track]))
               for start in (1.0, 3.0)), key=lambda result: result.cost)
    error = float(np.sqrt(np.mean(np.reshape(fit.fun, (-1, 2)) ** 2, axis=0)).max())
    acceleration, lag, scrub, effective_track = (float(x) for x in fit.x)
    params = DriveParams(acceleration, lag, scrub, effective_track, track)
    return DriveFit(params, _grip(base, config, physics_hz, solver_iterations, control_hz), error)


def _grip(base: WheeledBase, config: DiffDriveConfig, physics_hz: float, solver_iterations: int,
          control_hz: float) -> float:
    """The base's forward acceleration from rest, m/s^2, over one control step of a full forward command with
    :data:`GRIP_TORQUE_SCALE` times the motors' torque: the wheels slip, and the floor's friction sets it."""
    robot = DiffDriveRobot(replace(config, max_linear_speed=2.0), base)
    with _on_empty_floor(robot, physics_hz, solver_iterations) as sim:
        robot.apply_dynamics(DynamicsSample(motor_scale=GRIP_TORQUE_SCALE))
        robot.apply_action(np.array([1.0, 0.0]))
        sim.step(int(round(physics_hz / control_hz)))
        return float(robot.observe(robot.state())["velocity"][0]) * control_hz


@contextlib.contextmanager
def _on_empty_floor(robot: DiffDriveRobot, physics_hz: float, solver_iterations: int) -> Iterator[Sim]:
    """A Sim of its own with only a floor and ``robot`` at rest at the origin, closed on leaving."""
    sim = Sim(physics_hz=physics_hz, solver_iterations=solver_iterations, visuals=False)
    try:
        sim.add_ground(visual_size=2.0)
        robot.load(sim)
        robot.reset_pose(0.0, 0.0, 0.0)
        yield sim
    finally:
        sim.close()
