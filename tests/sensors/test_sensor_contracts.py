"""Sensor contracts that other suites' users trip over (the hard-case catalogue's sensor rows): the first reading
after a reset comes from the new poses, a beam with no return reads the documented value under every profile, hit
distances hold far from the origin, and the IMU carries nothing across a reset."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.sim import Sim

SENSORS = ("lidar", "camera", "imu")
WALL = {"shape": "box", "size": [0.2, 2.0, 0.5], "position": [1.0, 0.0]}
#: Scene A the robot drives in first; scene B moves the robot and the obstacle somewhere else.
SCENE_A = {"obstacles": [WALL], "start": [0.0, 0.0, 0.0], "goal": [2.0, 2.0]}
SCENE_B = {"obstacles": [{**WALL, "position": [-1.5, 1.0], "yaw": 0.6}], "start": [0.5, -1.0, 2.0],
           "goal": [-2.0, -2.0]}
#: Every named profile, and one with the slowest, most delayed sensors the clocks allow here.
LATE = {"profile": "harsh", "lidar": {"rate_hz": 2.0, "latency_steps": 3}, "imu": {"latency_steps": 2},
        "camera": {"rate_hz": 2.0, "latency_steps": 3}}
PROFILES = [*PROFILE_NAMES, LATE]


@pytest.mark.parametrize("noise", PROFILES, ids=lambda n: n if isinstance(n, str) else "late")
def test_the_first_observation_after_a_reset_is_the_new_scene_whatever_came_before(make_env, noise):
    """An env that drove an episode in scene A, then resets into scene B, observes exactly what a fresh env reset
    into B with the same seed observes: robot and obstacles at their new poses, no reading from before the reset
    held or delayed into the new episode."""
    kwargs = dict(sensors=SENSORS, camera_modes=("depth",), camera_size=(32, 24), noise=noise)
    used, fresh = make_env(**kwargs), make_env(**kwargs)
    used.reset(seed=1, options={"scene": SCENE_A})
    for _ in range(15):
        used.step(np.array([1.0, 0.5]))
    after, _ = used.reset(seed=2, options={"scene": SCENE_B})
    first, _ = fresh.reset(seed=2, options={"scene": SCENE_B})
    for key in first:
        np.testing.assert_array_equal(after[key], first[key], err_msg=key)


@pytest.mark.parametrize("env_id,kwargs", [
    ("ClutterFly-v1", dict(sensors=SENSORS, camera_modes=("depth",), camera_size=(32, 24), noise=LATE)),
    ("ClutterReach-v1", dict(noise=LATE)),
])
def test_every_env_observes_only_the_new_episode_after_a_reset(make_env, env_id, kwargs):
    """The same contract on the other envs, on generated scenes: after an episode, a reset with a seed observes
    what a fresh env's reset with that seed observes."""
    used, fresh = make_env(env_id, **kwargs), make_env(env_id, **kwargs)
    used.reset(seed=1)
    rng = np.random.default_rng(0)
    for _ in range(15):
        used.step(rng.uniform(-1.0, 1.0, used.action_space.shape))
    after, _ = used.reset(seed=2)
    first, _ = fresh.reset(seed=2)
    for key in first:
        np.testing.assert_array_equal(after[key], first[key], err_msg=key)


@pytest.mark.parametrize("noise", [*PROFILE_NAMES, {"profile": "harsh", "lidar": {"no_return": "inf"}}],
                         ids=lambda n: n if isinstance(n, str) else "harsh-inf")
def test_a_beam_with_no_return_reads_the_no_return_value_under_every_profile(make_env, noise):
    """With a 1 m LIDAR at the centre of an empty 6 m arena no beam meets anything; every beam reads the no-return
    value (the observation's 1, and ``max_range`` or ``inf`` in ``info``) at every step, with nothing added."""
    env = make_env(sensors=("lidar",), lidar_range=1.0, noise=noise)
    empty = {"obstacles": [], "start": [0.0, 0.0, 0.0], "goal": [2.0, 2.0]}
    inf = isinstance(noise, dict)
    obs, info = env.reset(seed=0, options={"scene": empty})
    for _ in range(20):
        assert np.all(obs["lidar"] == 1.0)
        assert np.all(info["lidar_ranges"] == (math.inf if inf else 1.0))
        obs, _, _, _, info = env.step(np.array([0.0, 1.0]))  # turn in place: the beams sweep the empty floor


def test_the_imu_reads_the_robot_at_rest_after_a_reset_at_speed(make_env):
    """The accelerometer is a finite difference of the velocity: a reset must not difference the new episode's
    rest against the last episode's speed. Clean sensors: gravity up and no rotation, to float32 rounding."""
    env = make_env(sensors=("imu",))
    env.reset(seed=0, options={"scene": SCENE_A})
    for _ in range(10):
        obs, *_ = env.step(np.array([1.0, 1.0]))
    assert np.abs(obs["imu"][3:6]).max() > 0.5  # it was turning
    obs, _ = env.reset(seed=0, options={"scene": SCENE_B})
    np.testing.assert_allclose(obs["imu"][:3], [0.0, 0.0, 9.81], rtol=0, atol=1e-6)
    np.testing.assert_allclose(obs["imu"][3:], 0.0, rtol=0, atol=1e-9)


@pytest.fixture
def sim():
    s = Sim(visuals=False)
    yield s
    s.close()


@pytest.mark.parametrize("offset", [0.0, 1e2, 1e4])
@pytest.mark.parametrize("caster", ["exact", "pybullet"])
def test_hit_distances_near_mid_and_far_hold_at_large_offsets(sim, offset, caster):
    """Level rays of 30 m toward box faces and cylinder sides at known distances (near, mid, the end of the range),
    ``offset`` metres out from the world origin in x and y. Both casters work in float64: box faces to rounding.
    A cylinder is exact to the exact caster; pybullet meets a 64-gon prism, whose sides lie between the circles of
    radius r cos(pi / 64) and r / cos(pi / 64)."""
    reach, half, radius = 30.0, np.array([0.05, 0.2, 0.25]), 0.25
    distances = np.array([0.3, 10.0, 29.7])
    lanes = np.array([[0.0, 1.0 * i, 0.0] for i in range(6)])
    starts = np.array([offset, offset, 0.25]) + lanes
    along = np.column_stack([distances, np.zeros(3), np.zeros(3)])
    sim.obstacles.add_static_boxes(half, (1, 1, 1, 1), list(starts[:3] + along + [half[0], 0.0, 0.0]))
    sim.obstacles.add_static_cylinders(radius, 0.5, (1, 1, 1, 1), list(starts[3:] + along + [radius, 0.0, 0.0]))
    got = reach * sim.rays.ray_hit_fractions(starts, starts + [reach, 0.0, 0.0], caster=caster)
    np.testing.assert_allclose(got[:3], distances, rtol=0, atol=1e-9)
    inner, outer = (0.0, 0.0) if caster == "exact" else (radius * (1.0 - math.cos(math.pi / 64)),
                                                         radius * (1.0 / math.cos(math.pi / 64) - 1.0))
    error = got[3:] - distances
    assert np.all(error >= -outer - 1e-9) and np.all(error <= inner + 1e-9), error
