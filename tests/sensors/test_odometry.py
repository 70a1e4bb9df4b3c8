"""Wheel odometry (clutter_gym.sensors.odometry): its dead reckoning against the closed-form arc, its encoder
counts, its per-episode errors against their parameters, its noise values against the source rows its noise module
carries, and a real drive against the simulator's ground truth."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from clutter_gym.noise.odometry import SENSOR_NOISE, OdometryNoise, encoder_angle, start_odometry_episode
from clutter_gym.noise.profiles import profile_sources, resolve_noise
from clutter_gym.sensors import WheelOdometry

RADIUS, TRACK = 0.05, 0.3


class FakeWheels:
    """A Sim that reports prescribed wheel angles (left, right) for a robot with one wheel a side."""

    def __init__(self):
        self.angles = np.zeros(2)
        self.actuation = self  # the Sim's part that reads joints

    def joint_states(self, body, joints):
        return self.angles.copy(), np.zeros(2)


def _odometry(noise=None):
    robot = SimpleNamespace(base=SimpleNamespace(left_wheels=["l"]), wheel_joints=[0, 1],
                            config=SimpleNamespace(wheel_radius=RADIUS, wheel_separation=TRACK))
    sim, state = FakeWheels(), SimpleNamespace(body=0)
    sensor = WheelOdometry(robot, noise)
    sensor.reset(sim, state, np.random.default_rng(0))
    return sensor, sim, state


def test_constant_wheel_speeds_give_the_closed_form_arc():
    """Each step turns the wheels by the same angles: the base drives an arc of radius R = (b/2)(dr+dl)/(dr-dl)
    through theta = n(dr-dl)/b, ending at (R sin theta, R (1 - cos theta))."""
    sensor, sim, state = _odometry()
    step_left, step_right, n = 0.2, 0.3, 50
    for _ in range(n):
        sim.angles += (step_left, step_right)
        reading = sensor.read(sim, state, np.random.default_rng(0))
    dl, dr = step_left * RADIUS, step_right * RADIUS
    theta = n * (dr - dl) / TRACK
    arc = TRACK / 2 * (dr + dl) / (dr - dl)
    np.testing.assert_allclose(reading[:3], [arc * math.sin(theta), arc * (1 - math.cos(theta)), theta], atol=1e-12)
    np.testing.assert_allclose(reading[3:], [(dr + dl) / 2, (dr - dl) / TRACK], atol=1e-15)


def test_encoders_count_whole_ticks():
    tick = 2 * math.pi / 135
    assert encoder_angle(10.5 * tick, 135) == pytest.approx(10 * tick)
    assert encoder_angle(-0.5 * tick, 135) == pytest.approx(-tick)
    assert encoder_angle(1.234, 0) == 1.234
    sensor, sim, state = _odometry(OdometryNoise(ticks_per_rev=135))
    sim.angles += (2.5 * tick, 7.9 * tick)  # 2 and 7 whole ticks
    reading = sensor.read(sim, state, None)
    assert reading[3] == pytest.approx((2 + 7) / 2 * tick * RADIUS)


def test_the_episode_errors_have_their_parameters_spread_and_a_clean_section_draws_nothing():
    rng = np.random.default_rng(1)
    draws = np.array([start_odometry_episode(rng, OdometryNoise(radius_sigma_frac=0.01, track_sigma_frac=0.05))
                      for _ in range(4000)])
    # 4,000 draws: the sample standard deviation is within 3.4% of sigma at 3 standard errors (sqrt(1/(2n)) = 1.1%)
    np.testing.assert_allclose(draws.std(axis=0), [0.01, 0.01, 0.05], rtol=0.034)
    np.testing.assert_allclose(draws.mean(axis=0), 1.0, atol=3 * 0.05 / math.sqrt(4000))
    rng = np.random.default_rng(2)
    assert start_odometry_episode(rng, OdometryNoise()) == (1.0, 1.0, 1.0)
    assert rng.bit_generator.state == np.random.default_rng(2).bit_generator.state


def test_a_believed_radius_error_scales_the_travel_and_a_track_error_the_turn():
    sensor, sim, state = _odometry(OdometryNoise(radius_sigma_frac=0.05, track_sigma_frac=0.1))
    left, right, track = start_odometry_episode(np.random.default_rng(0), sensor.noise)  # the reset's draws
    sim.angles += (1.0, 2.0)
    ds, dyaw = sensor.read(sim, state, None)[3:]
    assert ds == pytest.approx(0.5 * RADIUS * (left + 2.0 * right))
    assert dyaw == pytest.approx(RADIUS * (2.0 * right - left) / (TRACK * track))


@pytest.mark.parametrize("profile", ["nominal", "low-cost", "harsh"])
def test_every_odometry_value_cites_a_source_row_of_its_module(profile):
    values = profile_sources(profile)["odometry"]
    assert set(values) == {"ticks_per_rev", "radius_sigma_frac", "track_sigma_frac"}
    for key, (value, source) in values.items():
        rows = re.findall(r"\b(O\d+)\b", source)
        assert rows, (key, source)
        assert set(rows) <= set(SENSOR_NOISE.references), (key, source)
        assert getattr(resolve_noise(profile).section("odometry"), key) == value
    worse = [resolve_noise(p).section("odometry") for p in ("nominal", "low-cost", "harsh")]
    assert worse[0].ticks_per_rev > worse[1].ticks_per_rev > worse[2].ticks_per_rev


def test_a_drive_in_an_empty_arena_dead_reckons_what_the_simulator_did(make_env):
    """Clean odometry against ground truth, driving an arc on the diffbot: the encoders read the simulated wheels,
    which slip a little at full torque (measured: 4-5% more wheel travel than base travel while accelerating), so
    the bound is 10% of the distance and 0.1 rad."""
    env = make_env("ClutterNav-v1", sensors=["odometry"], arena_size=6.0, obstacle_density=0.0)
    env.reset(seed=1)
    robot = env.unwrapped.robot
    start = robot.state()
    for _ in range(30):
        *_, info = env.step(np.array([0.6, 0.4]))
    end = robot.state()
    moved = start.rotation.T @ (end.position - start.position)
    turned = math.atan2(end.rotation[1, 0], end.rotation[0, 0]) - math.atan2(start.rotation[1, 0],
                                                                              start.rotation[0, 0])
    x, y, yaw = info["odometry_pose"]
    assert math.hypot(x - moved[0], y - moved[1]) < 0.1 * math.hypot(*moved[:2])
    assert abs(math.remainder(yaw - turned, 2 * math.pi)) < 0.1


def test_only_a_wheeled_base_carries_odometry(make_env):
    with pytest.raises(ValueError, match="the odometry sensor reads a wheeled base's wheels; Quadrotor has none"):
        make_env("ClutterFly-v1", sensors=["odometry"])
