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
        ({"physics_hz": 120.0, "control_hz": 240.0}, r"physics_hz must be in \[control_hz=240.0, 10000\]"),
        ({"control_hz": 0.0}, r"control_hz must be in \(0, 1000\]"),
        ({"solver_iterations": 0}, r"solver_iterations must be an integer in \[1, 1000\]"),
        ({"sensors": ("lidar", "sonar")},
         r"unknown sensors \['sonar'\]; allowed: \('lidar', 'imu', 'camera', 'odometry'\)"),
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
        gym.make("ClutterNav-v1", **kwargs)


@pytest.mark.parametrize("env_id", ["ClutterNav-v1", "ClutterReach-v1", "ClutterFly-v1"])
@pytest.mark.parametrize(("physics_hz", "control_hz"), [(1.0, 1.0), (20.0, 20.0), (40.0, 20.0)])
def test_a_physics_rate_below_the_envs_floor_is_refused(env_id, physics_hz, control_hz):
    """Below its floor an env's stiffest dynamics break (docs/envs.md, "Physics rate"): ClutterFly's rate loop
    flips it, ClutterNav's wheels creep after a stop, the Panda sags and drifts."""
    with pytest.raises(ValueError, match=re.escape(f"physics_hz must be in [60, 10000] Hz for {env_id}")):
        gym.make(env_id, physics_hz=physics_hz, control_hz=control_hz)


@pytest.mark.parametrize("env_id", ["ClutterNav-v1", "ClutterReach-v1", "ClutterFly-v1"])
@pytest.mark.parametrize(("physics_hz", "control_hz", "least"), [(120.0, 1e-3, "0.12"), (10000.0, 5.0, "10")])
def test_more_than_a_thousand_physics_ticks_per_step_are_refused(env_id, physics_hz, control_hz, least):
    """One step holds one action for at most 1000 ticks: control_hz=1e-3 made a step 1,000 s of simulated time."""
    with pytest.raises(ValueError, match=re.escape(f"control_hz must be at least physics_hz / 1000 = {least} Hz")):
        gym.make(env_id, physics_hz=physics_hz, control_hz=control_hz)


def test_the_rate_limits_themselves_are_allowed(make_env):
    """The floor and the cap on ticks per step are in range."""
    from clutter_gym.clutter_nav import MIN_PHYSICS_HZ
    from clutter_gym.make_checks import MAX_TICKS_PER_STEP

    assert make_env("ClutterNav-v1", physics_hz=MIN_PHYSICS_HZ, control_hz=20.0).unwrapped.substeps == 3
    env = make_env("ClutterNav-v1", physics_hz=float(MAX_TICKS_PER_STEP), control_hz=1.0, sensors=())
    assert env.unwrapped.substeps == MAX_TICKS_PER_STEP


@pytest.mark.parametrize(("env_id", "name", "value"), [
    ("ClutterNav-v1", "terminate_on_collision", [1]),
    ("ClutterReach-v1", "shelf", "no"),
    ("ClutterReach-v1", "self_collision", "no"),
    ("ClutterReach-v1", "terminate_on_collision", 1),
    ("ClutterReach-v1", "observe_directions", None),
])
def test_switches_take_booleans_only(env_id, name, value):
    """A switch given "no" or [1] would otherwise switch by truthiness (on)."""
    with pytest.raises(ValueError, match=re.escape(f"{name} must be True or False, got {value!r}")):
        gym.make(env_id, **{name: value})


@pytest.mark.parametrize(("env_id", "name", "value"), [
    ("ClutterNav-v1", "arena_size", "5"),
    ("ClutterNav-v1", "arena_size", None),
    ("ClutterNav-v1", "physics_hz", "120"),
    ("ClutterNav-v1", "max_linear_speed", "fast"),
    ("ClutterNav-v1", "collision_padding", "0.1"),
    ("ClutterNav-v1", "contact_weight", True),
    ("ClutterNav-v1", "n_rays", None),
    ("ClutterReach-v1", "max_joint_speed", None),
    ("ClutterReach-v1", "n_obstacles", "3"),
])
def test_number_arguments_given_something_else_name_the_argument(env_id, name, value):
    with pytest.raises(ValueError, match=re.escape(f"{name} must be a number, got {value!r}")):
        gym.make(env_id, **{name: value})


def test_numpy_numbers_are_numbers(make_env):
    env = make_env("ClutterNav-v1", arena_size=np.float32(5.0), n_rays=np.int64(32),
                   noise={"lidar": {"range_sigma": np.float32(0.01), "latency_steps": np.int64(1)}})
    assert env.unwrapped.observation_space["lidar"].shape == (32,)
    assert env.unwrapped.noise.lidar.range_sigma == pytest.approx(0.01)
    assert env.unwrapped.noise.timing["lidar"].latency_steps == 1
    reach = make_env("ClutterReach-v1", n_obstacles=np.int64(3), solver_iterations=np.int64(10))
    assert reach.unwrapped.arena.spec.n_obstacles == 3


@pytest.mark.parametrize("lidar", [{"min_range": 2.0, "max_range": 1.0}, {"min_range": 4.0}])
def test_an_empty_lidar_window_is_refused_at_make(lidar):
    """A window with nothing in it would read "no return" forever; 4 m is beyond the default 3.5 m lidar_range."""
    with pytest.raises(ValueError, match="range window is empty"):
        gym.make("ClutterNav-v1", noise={"lidar": lidar})


def test_numpy_booleans_are_booleans():
    env = gym.make("ClutterReach-v1", shelf=np.bool_(False), terminate_on_collision=np.True_)
    assert env.unwrapped.arena.spec.shelf is False
    env.close()


def test_unknown_kwarg_is_named_with_the_closest_allowed_name_and_the_list():
    with pytest.raises(TypeError, match=r"'n_beams' \(did you mean 'n_rays'\?\); it takes \[.*'n_rays'"):
        gym.make("ClutterNav-v1", n_beams=10)
    with pytest.raises(TypeError, match=r"'obstacle_densty' \(did you mean 'obstacle_density'\?\)"):
        gym.make("ClutterFly-v1", obstacle_densty=0.1)
    with pytest.raises(TypeError, match=r"'zzz'; it takes \["):  # nothing close: the list alone
        gym.make("ClutterReach-v1", zzz=1)


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
