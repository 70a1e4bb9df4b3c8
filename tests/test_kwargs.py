"""Bad make-time arguments fail at gym.make with the field and its allowed range in the message."""

from __future__ import annotations

import math
import re

import gymnasium as gym
import numpy as np
import pytest


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"n_rays": -1}, r"n_rays must be an integer in \[1, 4096\]"),
        ({"n_rays": 0}, r"n_rays must be an integer in \[1, 4096\]"),
        ({"n_rays": 2.5}, r"n_rays must be an integer"),
        ({"physics_hz": 100.0, "control_hz": 30.0}, r"physics_hz must be an integer multiple of control_hz"),
        ({"physics_hz": 10.0, "control_hz": 20.0}, r"physics_hz must be in \[control_hz"),
        ({"control_hz": 0.0}, r"control_hz must be in \(0, 1000\]"),
        ({"solver_iterations": 0}, r"solver_iterations must be an integer in \[1, 1000\]"),
        ({"sensors": ("lidar", "sonar")}, r"unknown sensors \['sonar'\]; allowed: \('lidar', 'imu', 'camera'\)"),
        ({"sensors": "lidar"}, r"sensors must be a tuple of names"),
        ({"sensors": ("imu", "imu")}, r"must not repeat"),
        ({"obstacle_density": 0.5}, r"obstacle_density must be in \[0, 0.3\]"),
        ({"obstacle_density": -0.1}, r"obstacle_density must be in \[0, 0.3\]"),
        ({"arena_size": 1.0}, r"arena_size must be in \[2, 30\] metres"),
        ({"arena_size": float("nan")}, r"arena_size must be in \[2, 30\] metres"),
        ({"lidar_range": 0.01}, r"lidar_range must be in \(0.12, 100\] metres"),
        ({"lidar_fov": 7.0}, r"lidar_fov must be in \(0, 2\*pi\] radians"),
        ({"lidar_mount_height": 5.0}, r"lidar_mount_height must be in \[-0.5, 2\] metres"),
        ({"max_linear_speed": 0.0}, r"max_linear_speed must be in \(0, 2.0\]"),
        ({"success_radius": 0.0}, r"success_radius must be in \(0, 2\] metres"),
        ({"clearance_margin": -1.0}, r"clearance_margin must be in \[0, 1\] metres"),
        ({"contact_weight": -1.0}, r"reward weight contact must be in \[0, 1e4\]"),
        ({"contact_tolerance": 1.0}, r"contact_tolerance must be in \[0, 0.05\] metres"),
        ({"render_mode": "ascii"}, r"render_mode must be None or one of \('human', 'rgb_array'\)"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*render_mode:UserWarning")
def test_invalid_kwargs_raise_at_make(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        gym.make("ClutterNav-v0", **kwargs)


@pytest.mark.parametrize(("env_id", "name", "value"), [
    ("ClutterNav-v0", "terminate_on_collision", [1]),
    ("ClutterReach-v0", "shelf", "no"),
    ("ClutterReach-v0", "self_collision", "no"),
    ("ClutterReach-v0", "terminate_on_collision", 1),
    ("ClutterReach-v0", "observe_directions", None),
])
def test_switches_take_booleans_only(env_id, name, value):
    """A switch given "no" or [1] would otherwise switch by truthiness (on)."""
    with pytest.raises(ValueError, match=re.escape(f"{name} must be True or False, got {value!r}")):
        gym.make(env_id, **{name: value})


def test_numpy_booleans_are_booleans():
    env = gym.make("ClutterReach-v0", shelf=np.bool_(False), terminate_on_collision=np.True_)
    assert env.unwrapped.arena.spec.shelf is False
    env.close()


def test_unknown_kwarg_is_named():
    with pytest.raises(TypeError, match="n_beams"):
        gym.make("ClutterNav-v0", n_beams=10)


@pytest.mark.parametrize("sensors", [(), ("imu",), ("lidar",), ("imu", "lidar")])
def test_only_listed_sensors_exist(sensors, make_env):
    env = make_env(sensors=sensors)
    obs, info = env.reset(seed=0)
    assert set(obs) == set(sensors) | {"goal", "velocity"}
    assert set(env.observation_space.spaces) == set(obs)
    assert ("lidar_ranges" in info) == ("lidar" in sensors)


def test_lidar_kwargs_shape_the_scan(make_env):
    env = make_env(n_rays=16, lidar_fov=math.pi, lidar_range=3.0)
    obs, info = env.reset(seed=0)
    assert obs["lidar"].shape == (16,)
    assert info["lidar_ranges"].max() <= 3.0 + 1e-9
    np.testing.assert_allclose(obs["lidar"], info["lidar_ranges"] / 3.0, rtol=1e-6)
