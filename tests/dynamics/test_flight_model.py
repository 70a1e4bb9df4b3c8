"""The reduced multirotor model against closed forms (hover, free fall, a torque-free spin), its mixer against the
flight controller's, and its free flight against pybullet's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.dynamics import flight_model as fm
from clutter_gym.dynamics.choice import AUTO_FLIGHT_BOUND
from clutter_gym.dynamics.flight_check import PROBE_OFFSETS, compare_flights, flight_gap
from clutter_gym.robots import MultirotorConfig
from clutter_gym.robots.rate_loop import Mixer, allocation
from clutter_gym.robots.registry import resolve_robot
from clutter_gym.sim import GRAVITY

PHYSICS_HZ, CONTROL_HZ = 240.0, 30.0
SUBSTEPS = int(PHYSICS_HZ / CONTROL_HZ)


def quadrotor(**config):
    return resolve_robot("quadrotor", "multirotor", "ClutterFly-v1")(MultirotorConfig(**config))


def at_rest(robot, speeds, height=2.0):
    """A flight state at rest, level, ``height`` m up, its rotors at ``speeds``."""
    state = np.zeros(fm.state_size(len(robot.model.rotor_links)))
    state[fm.COM + 2], state[fm.QUAT + 3], state[fm.RATIO] = height, 1.0, 1.0
    state[fm.SPEEDS:] = speeds
    return state


def test_a_hover_holds_its_place():
    robot = quadrotor()
    state = at_rest(robot, robot.hover_speeds(GRAVITY))
    hover = robot.hover_action(GRAVITY)
    command = np.array([0.5 * (hover[0] + 1.0) * robot._max_collective, 0.0, 0.0, 0.0])
    fm.flight_ticks(state, fm.flight_params(robot, PHYSICS_HZ, GRAVITY), fm.rotor_table(robot), command, 240 * 5)
    # the hover speeds carry the weight to rounding: 5 s later the airframe has moved by less than a micrometre
    assert np.abs(state[fm.COM:fm.COM + 3] - (0.0, 0.0, 2.0)).max() < 1e-6
    np.testing.assert_allclose(state[fm.QUAT:fm.QUAT + 4], (0.0, 0.0, 0.0, 1.0), atol=1e-9)


def test_with_its_rotors_stopped_it_falls_as_semi_implicit_euler_integrates_free_fall():
    robot = quadrotor(control="motors")
    state = at_rest(robot, [0.0] * 4, height=50.0)
    dt, ticks = 1.0 / PHYSICS_HZ, 240 * 2
    fm.flight_ticks(state, fm.flight_params(robot, PHYSICS_HZ, GRAVITY), fm.rotor_table(robot), np.zeros(4), ticks)
    t = ticks * dt
    # the closed form of the integrator (velocity first, then position): z0 - g dt^2 n (n + 1) / 2, which is the
    # continuous fall 1/2 g t^2 plus the scheme's known lead of 1/2 g dt t
    assert state[fm.COM + 2] == pytest.approx(50.0 - GRAVITY * (0.5 * t * t + 0.5 * dt * t), abs=1e-9)
    assert state[fm.LIN + 2] == pytest.approx(-GRAVITY * t, abs=1e-9)
    assert np.abs(state[fm.COM:fm.COM + 2]).max() == 0.0


def test_a_spin_about_a_principal_axis_turns_at_a_constant_rate():
    """Equal rotor speeds give no torque (two spin each way); a yaw rate about body z, a principal axis, then stays
    constant and the attitude turns by exactly rate x t (the exact rotation of each tick)."""
    robot = quadrotor(control="motors")
    speeds = robot.hover_speeds(GRAVITY)
    state = at_rest(robot, speeds, height=50.0)
    state[fm.ANG + 2] = 2.0
    ticks = 240 * 3
    fm.flight_ticks(state, fm.flight_params(robot, PHYSICS_HZ, GRAVITY), fm.rotor_table(robot), np.array(speeds), ticks)
    x, y, z, w = state[fm.QUAT:fm.QUAT + 4]
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    assert yaw == pytest.approx(math.remainder(2.0 * ticks / PHYSICS_HZ, 2 * math.pi), abs=1e-9)
    assert state[fm.ANG + 2] == pytest.approx(2.0, abs=1e-12) and abs(x) + abs(y) < 1e-12


@pytest.mark.parametrize("n_rotors", [4, 6])
def test_the_compiled_mixer_gives_the_flight_controllers_thrusts(n_rotors):
    """Within the rotors' range and in each of its saturation branches (roll and pitch scaled, yaw given up,
    collective moved), on a quadrotor and a hexarotor."""
    angles = np.linspace(0.0, 2 * np.pi, n_rotors, endpoint=False) + np.pi / n_rotors
    positions = 0.05 * np.column_stack([np.cos(angles), np.sin(angles)])
    spin = np.array([(-1.0) ** i for i in range(n_rotors)])
    mixer = Mixer(allocation(positions, spin, 0.006), 0.0, 0.15)
    table = np.column_stack([np.zeros((n_rotors, 4)), np.array(mixer.torque_rows), np.array(mixer.shares)])
    rng = np.random.default_rng(0)
    out = np.empty(n_rotors)
    for _ in range(500):
        thrust = rng.uniform(-0.1, 0.15 * n_rotors * 1.2)
        torque = rng.uniform(-1, 1, 3) * rng.choice([1e-4, 3e-3, 3e-2]) * (1, 1, 0.1)
        fm.mix(thrust, *torque, table, mixer.min_thrust, mixer.max_thrust, out)
        np.testing.assert_allclose(out, mixer.thrusts(thrust, torque.tolist()), atol=1e-12)


@pytest.mark.parametrize("config", [{}, {"aero": ("drag", "ground_effect"), "observe_thrust_ratio": True},
                                    {"control": "motors"}])
def test_it_flies_as_pybullet_flies_in_free_air(config):
    """The same equations as pybullet's floating base (semi-implicit Euler, the gyroscopic term, the exact rotation
    of a tick, the bound on each velocity coordinate): 4 s of seeded commands, rolls and, with the motors commanded
    directly, a tumble past 100 rad/s, leave the two within a micrometre and a microradian."""
    robot = quadrotor(**config)
    offsets = np.random.default_rng(1).uniform(-0.5, 0.5, (16, 4))
    full, reduced = compare_flights(robot.model, robot.config, PHYSICS_HZ, 10, CONTROL_HZ, offsets, 0.25)
    assert np.linalg.norm(full[:, :3] - full[0, :3], axis=1).max() > 1.0  # it flew somewhere
    assert np.abs(full[:, :3] - reduced[:, :3]).max() < 1e-6
    # q and -q are one attitude: the angle between the two, 2 acos |q1 . q2|
    assert (2.0 * np.arccos(np.minimum(1.0, np.abs((full[:, 3:] * reduced[:, 3:]).sum(axis=1))))).max() < 1e-6


def test_auto_checks_the_model_on_its_probe():
    robot = quadrotor()
    assert flight_gap(robot.model, robot.config, PHYSICS_HZ, 10, CONTROL_HZ) < AUTO_FLIGHT_BOUND
    assert len(PROBE_OFFSETS) * 0.25 == 2.0
