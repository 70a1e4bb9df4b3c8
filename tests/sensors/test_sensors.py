"""LIDAR geometry and IMU readings against their definitions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import empty_scene

from clutter_gym.sensors import LidarConfig
from clutter_gym.sim import MAX_RAY_BATCH, Sim

G = 9.81


def test_full_circle_lidar_does_not_repeat_a_beam():
    angles = LidarConfig(n_rays=8).angles
    np.testing.assert_allclose(angles, -math.pi + 2 * math.pi * np.arange(8) / 8)


def test_partial_fov_spans_its_ends():
    angles = LidarConfig(n_rays=5, fov=math.pi / 2).angles
    np.testing.assert_allclose(angles, np.linspace(-math.pi / 4, math.pi / 4, 5))


def test_open_arena_scan_sees_the_walls_at_their_distance(make_env):
    env = make_env(lidar_range=5.0)
    _, info = env.reset(options={"scene": empty_scene()})
    angles = env.unwrapped.sensors[0].config.angles
    ranges = info["lidar_ranges"]
    # lidar at (0.05, 0), walls at |x|, |y| = 3: along +x the wall is 2.95 m away, along -x 3.05 m
    assert ranges[np.argmin(np.abs(angles))] == pytest.approx(2.95, abs=1e-3)
    assert ranges[np.argmin(np.abs(np.abs(angles) - math.pi))] == pytest.approx(3.05, abs=1e-3)
    assert ranges[np.argmin(np.abs(angles - math.pi / 2))] == pytest.approx(3.0, abs=1e-3)


def test_imu_at_rest_reads_gravity_up_and_no_rotation(make_env):
    env = make_env()
    obs, _ = env.reset(options={"scene": empty_scene()})
    np.testing.assert_allclose(obs["imu"], [0, 0, G, 0, 0, 0], atol=1e-6)  # placed exactly level, at rest
    for _ in range(20):
        obs, *_ = env.step(np.zeros(2))
    np.testing.assert_allclose(obs["imu"][:3], [0, 0, G], atol=1e-3)  # settled, still level
    np.testing.assert_allclose(obs["imu"][3:], 0, atol=1e-3)


def test_gyro_matches_the_measured_yaw_rate(make_env):
    """Each gyro sample (the rate at the end of a step) is close to the yaw change over that step, and their
    means agree to 0.1%."""
    env = make_env()
    env.reset(options={"scene": empty_scene()})
    for _ in range(20):  # spin up
        env.step(np.array([0.0, 0.5]))
    yaw = [env.unwrapped.robot.state().yaw]
    gyro = []
    for _ in range(40):
        obs, *_ = env.step(np.array([0.0, 0.5]))
        yaw.append(env.unwrapped.robot.state().yaw)
        gyro.append(obs["imu"][5])
    rate = np.diff(np.unwrap(yaw)) * 20
    np.testing.assert_allclose(gyro, rate, atol=0.02)
    assert np.mean(gyro) == pytest.approx(np.mean(rate), rel=1e-3)
    assert np.mean(rate) == pytest.approx(1.0, rel=0.01)  # commanded 0.5 * 2.0 rad/s


def test_accelerometer_integrates_to_the_speed_gained(make_env):
    """From rest, the integral of f_x over the speed-up equals the forward speed reached."""
    env = make_env()
    env.reset(options={"scene": empty_scene()})
    dt = 1 / 20
    fx = []
    for _ in range(20):
        obs, *_ = env.step(np.array([1.0, 0.0]))
        fx.append(obs["imu"][0])
    speed = obs["velocity"][0]
    assert speed == pytest.approx(0.5, rel=0.01)  # commanded max_linear_speed
    assert np.sum(fx) * dt == pytest.approx(speed, rel=5e-3)


@pytest.mark.parametrize("n", [MAX_RAY_BATCH, MAX_RAY_BATCH + 1, 2 * MAX_RAY_BATCH + 1])
def test_ray_batches_of_any_size_answer_every_ray(n):
    """pybullet answers 16,384 rays in one call with an empty list; the Sim splits batches so none is lost."""
    sim = Sim()
    sim.obstacles.add_static_boxes([0.5, 0.5, 0.5], (1.0, 1.0, 1.0, 1.0), [(2.0, 0.0, 0.5)])
    starts = np.zeros((n, 3)) + [0.0, 0.0, 0.5]
    ends = starts + [4.0, 0.0, 0.0]
    ends[1::2, 0] = -4.0  # every other ray points away and hits nothing
    fractions = sim.rays.ray_hit_fractions(starts, ends)
    sim.close()
    assert fractions.shape == (n,)
    np.testing.assert_allclose(fractions[0::2], 1.5 / 4.0, atol=1e-6)
    np.testing.assert_array_equal(fractions[1::2], 1.0)


def test_lidar_larger_than_one_ray_batch_reads_every_channel(make_env):
    """4,096 x 5 = 20,480 beams, more than one rayTestBatch call takes: with no vertical spread every channel is the
    same scan, so every channel, the ones past the first 16,384 beams too, must read the 2D scanner's scan."""
    multi = make_env(lidar_range=5.0, n_rays=4096, lidar_channels=5, lidar_vertical_fov=0.0)
    flat = make_env(lidar_range=5.0, n_rays=4096)
    scene = {"scene": empty_scene(obstacles=[{"shape": "box", "size": [0.4, 0.4, 0.5], "position": [1.0, 0.3]}])}
    ranges = multi.reset(options=scene)[1]["lidar_ranges"]
    scan = flat.reset(options=scene)[1]["lidar_ranges"]
    assert ranges.shape == (5, 4096) and np.all(np.isfinite(ranges))
    for channel in ranges:
        np.testing.assert_array_equal(channel, scan)


def test_multichannel_lidar_middle_channel_is_the_2d_scan(make_env):
    flat, multi = make_env(lidar_range=5.0), make_env(lidar_range=5.0, lidar_channels=3, lidar_vertical_fov=0.3)
    scene = {"scene": empty_scene()}
    obs_flat, _ = flat.reset(options=scene)
    obs_multi, info = multi.reset(options=scene)
    assert obs_multi["lidar"].shape == (3, 64) and multi.observation_space["lidar"].shape == (3, 64)
    np.testing.assert_allclose(obs_multi["lidar"][1], obs_flat["lidar"], atol=1e-6)
    # the lowest channel looks 0.15 rad down from 0.21 m: its beams meet the floor 0.21 / sin(0.15) = 1.405 m away
    np.testing.assert_allclose(info["lidar_ranges"][0], 0.21 / math.sin(0.15), rtol=1e-4)
