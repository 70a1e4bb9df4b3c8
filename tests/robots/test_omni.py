"""The omnidirectional base (clutter_gym.robots.omni) against its kinematics: it tracks a body-frame velocity in
any direction, a constant command with a yaw rate settles where a first-order lag of a rotating vector settles,
it holds still at a zero command, a wall stops it, and a spec of kind ``omni`` reads as the shipped one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.assets import asset_path
from clutter_gym.robots.omni import omnibot
from clutter_gym.robots.registry import resolve_robot

OPEN = {"robot": "omnibot", "arena_size": 8.0, "obstacle_density": 0.0, "sensors": ["lidar"]}
#: the base at the centre of the empty 8 m arena, facing +x: 4 m from every wall
CENTRE = {"scene": {"start": [0.0, 0.0, 0.0], "goal": [3.0, 3.0], "obstacles": []}}


def _yaw(rotation):
    return math.atan2(rotation[1, 0], rotation[0, 0])


def _drive(env, action, steps):
    for _ in range(steps):
        obs, *_, info = env.step(np.asarray(action, dtype=np.float32))
    return obs, info


@pytest.mark.parametrize("direction", [0.0, 0.5 * math.pi, 0.75 * math.pi, -0.3])
def test_it_drives_any_direction_of_the_floor_without_turning(make_env, direction):
    """Settled at 0.4 m/s along ``direction`` (base frame): the velocity entry reads the command within 1%, the
    base moved along that direction and its heading held (the response time is 0.1 s, the ramp 0.2 s at 2 m/s^2, so
    2 s is settled)."""
    env = make_env("ClutterNav-v1", **OPEN)
    env.reset(seed=3, options=CENTRE)
    robot = env.unwrapped.robot
    start = robot.state()
    command = 0.8 * np.array([math.cos(direction), math.sin(direction), 0.0])  # 0.8 of the 0.5 m/s maximum
    obs, info = _drive(env, command, 40)
    np.testing.assert_allclose(obs["velocity"], [*(0.4 * command[:2] / 0.8), 0.0], atol=0.004)
    end = robot.state()
    moved = start.rotation.T @ (end.position - start.position)
    assert math.atan2(moved[1], moved[0]) == pytest.approx(direction, abs=0.01)
    assert abs(_yaw(end.rotation) - _yaw(start.rotation)) < 0.01
    assert info["n_contacts"] == 0 and abs(end.position[2] - 0.05) < 1e-3


def test_a_turning_command_settles_as_a_first_order_lag_of_a_rotating_vector(make_env):
    """Commanded (v, 0) in the base frame while turning at w: in the world the command rotates at w, and a
    first-order tracker of time constant tau settles at the command times 1 / (1 + i w tau), so the base frame
    reads speed v / sqrt(1 + (w tau)^2), turned by -atan(w tau), and the yaw rate w exactly (its own loop)."""
    env = make_env("ClutterNav-v1", **OPEN)
    env.reset(seed=4, options=CENTRE)
    v, w, tau = 0.3, 1.0, 0.1
    obs, _ = _drive(env, [v / 0.5, 0.0, w / 2.0], 60)
    speed, lag = v / math.hypot(1.0, w * tau), math.atan(w * tau)
    np.testing.assert_allclose(obs["velocity"], [speed * math.cos(lag), -speed * math.sin(lag), w], atol=0.006)


def test_a_zero_command_stops_the_base_and_holds_it(make_env):
    env = make_env("ClutterNav-v1", **OPEN)
    env.reset(seed=5, options=CENTRE)
    _drive(env, [1.0, 0.5, 0.5], 20)
    _drive(env, [0.0, 0.0, 0.0], 20)  # 1 s: stopped from 0.5 m/s at 2 m/s^2 in 0.25 s
    robot = env.unwrapped.robot
    before = robot.state()
    obs, _ = _drive(env, [0.0, 0.0, 0.0], 40)
    after = robot.state()
    assert np.linalg.norm(after.position - before.position) < 1e-3
    np.testing.assert_allclose(obs["velocity"], 0.0, atol=1e-3)


def test_a_wall_stops_it_without_passing_through(make_env):
    """Driven sideways at full speed into a box: contact is reported and the chassis never sinks in more than the
    contact tolerance allows pybullet's solver (5 mm)."""
    scene = {"start": [0.0, 0.0, 0.0], "goal": [3.0, 3.0],
             "obstacles": [{"shape": "box", "position": [0.0, 0.6], "size": [1.0, 0.2, 0.5]}]}
    env = make_env("ClutterNav-v1", **{**OPEN, "terminate_on_collision": False})
    env.reset(seed=0, options={"scene": scene})
    touched, deepest = False, 0.0
    for _ in range(60):
        _, _, _, _, info = env.step(np.array([0.0, 1.0, 0.0], dtype=np.float32))
        touched |= info["n_contacts"] > 0
        deepest = min(deepest, info["min_clearance"])
    assert touched and deepest > -0.005
    assert env.unwrapped.robot.state().position[1] < 0.6 - 0.1 - 0.19 + 0.005  # the box's face less the footprint


def test_an_omni_spec_reads_as_the_shipped_base(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    model = resolve_robot({"kind": "omni", "urdf": str(asset_path("robots/omnibot.urdf")), "name": "mine"}, "omni",
                          "ClutterNav-v1")
    shipped = omnibot()
    assert model.footprint_radius == pytest.approx(shipped.footprint_radius, abs=1e-3)
    assert model.base_height == pytest.approx(shipped.base_height, abs=1e-9)
    assert set(shipped.tracked_links) <= set(model.tracked_links)  # the spec also tracks its camera link
    with pytest.raises(ValueError, match=r"max_acceleration must be a number in \[0.01, 100\]"):
        resolve_robot({"kind": "omni", "urdf": str(asset_path("robots/omnibot.urdf")), "max_acceleration": 0},
                      "omni", "ClutterNav-v1")


def test_the_monitor_needs_a_differential_drive(make_env):
    with pytest.raises(ValueError, match="safety_horizon > 0 needs a differential drive"):
        make_env("ClutterNav-v1", robot="omnibot", safety_horizon=0.3)
