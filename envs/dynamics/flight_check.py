"""How closely a multirotor's reduced model (:mod:`clutter_gym.dynamics.flight_model`) flies as pybullet flies it: a
fixed probe of commands flown by both in free air, from the same start. Nothing is fitted (the model takes every
number from the robot's model and URDF); the probe checks that the two agree for this airframe, controller and
rate, and ``dynamics="auto"`` takes the model only where they do. Done once per airframe, config and rates in a
process (cached).
"""

from __future__ import annotations

import functools

import numpy as np

from clutter_gym.dynamics.flight_model import (
    COM,
    QUAT,
    RATIO,
    SPEEDS,
    flight_params,
    flight_ticks,
    rotor_table,
    state_size,
)
from clutter_gym.robots.multirotor import Multirotor, MultirotorConfig
from clutter_gym.robots.multirotor_model import MultirotorModel
from clutter_gym.sim import Sim

#: s, the probe's length, and how long it holds each of its commands
PROBE_SECONDS, HOLD_SECONDS = 2.0, 0.25
#: the probe's commands as offsets from the hover action (normalised), drawn once from a fixed seed
PROBE_OFFSETS = np.random.default_rng(20261129).uniform(-0.5, 0.5, size=(int(PROBE_SECONDS / HOLD_SECONDS), 4))


@functools.lru_cache(maxsize=16)
def flight_gap(model: MultirotorModel, config: MultirotorConfig, physics_hz: float, solver_iterations: int,
               control_hz: float) -> float:
    """The largest distance (m) between the centre of mass as pybullet flies the probe and as the reduced model
    flies it, over the probe's control steps."""
    full, reduced = compare_flights(model, config, physics_hz, solver_iterations, control_hz, PROBE_OFFSETS,
                                    HOLD_SECONDS)
    return float(np.linalg.norm(full[:, :3] - reduced[:, :3], axis=1).max())


def compare_flights(model: MultirotorModel, config: MultirotorConfig, physics_hz: float, solver_iterations: int,
                    control_hz: float, offsets: np.ndarray, hold: float, height: float = 100.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Fly the airframe from rest, ``height`` metres up in empty space, through the actions ``hover + offset`` of
    ``offsets`` (normalised, clipped), each held ``hold`` seconds, in pybullet and by the reduced model.

    Returns:
        (pybullet's, the model's) centre of mass and attitude quaternion (x, y, z, w) after each control step, (n, 7).
    """
    robot = Multirotor(model, config)
    sim = Sim(physics_hz=physics_hz, solver_iterations=solver_iterations, visuals=False)
    try:
        robot.load(sim)
        robot.reset_to((0.0, 0.0, height, 0.0))
        params, rotors = flight_params(robot, physics_hz, sim.gravity), rotor_table(robot)
        state = np.zeros(state_size(len(rotors)))
        state[COM:COM + 3], state[QUAT:QUAT + 4] = sim.base_pose(robot.body)
        state[SPEEDS:], state[RATIO] = robot.rotor_speeds, 1.0
        substeps = int(round(physics_hz / control_hz))
        steps = max(1, int(round(hold * control_hz)))
        hover = robot.hover_action(sim.gravity)
        full, reduced = np.empty((len(offsets) * steps, 7)), np.empty((len(offsets) * steps, 7))
        for i, offset in enumerate(offsets):
            robot.apply_action(np.clip(hover + offset, -1.0, 1.0))
            for j in range(i * steps, (i + 1) * steps):
                flight_ticks(state, params, rotors, robot.held_command(), substeps)
                for _ in range(substeps):
                    robot.before_tick()
                    sim.step()
                position, quaternion = sim.base_pose(robot.body)
                full[j] = (*position, *quaternion)
                reduced[j] = state[COM:QUAT + 4]
        return full, reduced
    finally:
        sim.close()
