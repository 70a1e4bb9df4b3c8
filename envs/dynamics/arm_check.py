"""How closely an arm's reduced model (:mod:`clutter_gym.dynamics.arm_model`) moves the arm as pybullet does: a fixed
probe of joint commands driven by both, in empty space, from the arm's ready pose. ``dynamics="auto"`` takes the
model only where the end effector stays within its bound. Done once per arm, config and rates in a process (cached).
"""

from __future__ import annotations

import functools

import numpy as np

from clutter_gym.dynamics.arm_model import arm_ticks
from clutter_gym.robots.arm import Arm, ArmConfig
from clutter_gym.robots.arm_model import ArmModel
from clutter_gym.sim import Sim

#: s, the probe's length, and how long it holds each of its commands
PROBE_SECONDS, HOLD_SECONDS = 3.0, 0.25
#: the probe's commands (normalised, within 0.7 of full scale), drawn once from a fixed seed; one column per joint
#: of the largest arm the probe serves (an arm takes its first columns)
PROBE_COMMANDS = np.random.default_rng(20261129).uniform(-0.7, 0.7, size=(int(PROBE_SECONDS / HOLD_SECONDS), 16))


@functools.lru_cache(maxsize=16)
def arm_gap(model: ArmModel, config: ArmConfig, physics_hz: float, solver_iterations: int, control_hz: float) -> float:
    """The largest distance (m) between the end effector as pybullet drives the probe and as the reduced model
    drives it, over the probe's control steps."""
    full, reduced = compare_drives(model, config, physics_hz, solver_iterations, control_hz, PROBE_COMMANDS,
                                   HOLD_SECONDS)
    return float(np.linalg.norm(full - reduced, axis=1).max())


def compare_drives(model: ArmModel, config: ArmConfig, physics_hz: float, solver_iterations: int, control_hz: float,
                   commands: np.ndarray, hold: float) -> tuple[np.ndarray, np.ndarray]:
    """Drive two copies of the arm from its ready pose through ``commands`` (normalised actions; an arm takes as many
    columns as its action has), each held ``hold`` seconds: one in pybullet, one by the reduced model (pybullet's
    forward kinematics placing its links).

    Returns:
        (pybullet's, the model's) end-effector position after each control step, (n, 3) m.
    """
    arms, sims = [], []
    try:
        for _ in range(2):
            arm = Arm(model, config, control_dt=1.0 / control_hz)
            sim = Sim(physics_hz=physics_hz, solver_iterations=solver_iterations, visuals=False)
            sims.append(sim)
            arm.load(sim)
            arm.reset_to(tuple(model.ready))
            arms.append(arm)
        full, reduced = arms
        substeps = int(round(physics_hz / control_hz))
        steps = max(1, int(round(hold * control_hz)))
        width = full.action_space.shape[0]
        out = np.empty((2, len(commands) * steps, 3))
        for i, command in enumerate(commands):
            for j in range(i * steps, (i + 1) * steps):
                full.apply_action(command[:width])
                sims[0].step(substeps)
                reduced.apply_action(command[:width])
                state = reduced.state()
                q, v = state.joint_position.copy(), state.joint_velocity.copy()
                arm_ticks(q, v, *reduced.held_command(), 1.0 / physics_hz, substeps)
                sims[1].actuation.reset_joints(reduced.body, reduced.arm_joints, q.tolist(), v.tolist())
                out[0, j] = full.ee_position(full.state())
                out[1, j] = reduced.ee_position(reduced.state())
        return out[0], out[1]
    finally:
        for sim in sims:
            sim.close()
