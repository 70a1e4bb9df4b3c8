"""Sensor timing and the action channel as pure objects: update counts, delays, first readings."""

from __future__ import annotations

import numpy as np
import pytest

from clutter_gym.noise.action import ActionChannel, ActionNoise
from clutter_gym.noise.timing import SensorTiming
from clutter_gym.sensors.timing import SampleHoldDelay


def run(timing: SensorTiming, steps: int, seed: int = 0, dt: float = 0.05) -> list:
    clock = SampleHoldDelay(timing, dt)
    clock.reset(np.random.default_rng(seed))
    return [clock.push(k if clock.due() else None) for k in range(steps)]


@pytest.mark.parametrize("rate, expected", [(15.0, 0.75), (5.0, 0.25), (7.0, 0.35)])
def test_update_rate_below_the_control_rate_is_kept_on_average(rate, expected):
    out = run(SensorTiming(rate_hz=rate), 20_000)
    updates = sum(1 for a, b in zip(out, out[1:]) if a != b)
    assert updates / len(out) == pytest.approx(expected, abs=1e-3)  # a deterministic schedule: off by one at most


def test_fast_sensors_update_every_step_and_draw_nothing():
    rng = np.random.default_rng(1)
    before = rng.bit_generator.state
    clock = SampleHoldDelay(SensorTiming(rate_hz=40.0), 0.05)
    clock.reset(rng)
    assert rng.bit_generator.state == before
    assert run(SensorTiming(rate_hz=40.0), 10) == list(range(10))


def test_phase_differs_between_episodes():
    schedules = {tuple(run(SensorTiming(rate_hz=5.0), 8, seed=s)) for s in range(20)}
    assert len(schedules) == 4  # a 4-step period has four phases; 20 episodes see all of them


def test_latency_delays_by_whole_steps_and_the_first_reading_fills_the_line():
    assert run(SensorTiming(latency_steps=2), 6) == [0, 0, 0, 1, 2, 3]


def test_action_latency_and_noise():
    channel = ActionChannel(ActionNoise(latency_steps=1), 2)
    channel.reset()
    rng = np.random.default_rng(0)
    a, b = np.array([0.5, -0.5]), np.array([1.0, 0.0])
    np.testing.assert_array_equal(channel.send(a, rng), [0.0, 0.0])  # the robot starts at rest
    np.testing.assert_array_equal(channel.send(b, rng), a)
    noisy = ActionChannel(ActionNoise(sigma=0.05), 2)
    noisy.reset()
    draws = np.array([noisy.send(np.zeros(2), rng) for _ in range(50_000)])
    assert abs(draws.std() / 0.05 - 1.0) < 0.02  # 100,000 normals: relative standard error 0.2%
    clean = ActionChannel(ActionNoise(), 2)
    assert clean.send(a, rng) is a
