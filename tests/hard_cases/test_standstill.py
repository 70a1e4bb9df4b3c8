"""A base commanded to stand still stands still, whatever it did before and whichever way it faces.

Before the standstill hold, velocity motors at zero target and re-anchored friction let the robot creep up to
8.6 mm and 17 mrad in 20 s, depending on its heading (Bullet's friction directions follow the world axes).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from helpers import empty_scene

from benchmarks.hard_cases.scenes.standstill import base_pose, standstill_drift
from benchmarks.hard_cases.scenes.stepping import STILL


@pytest.fixture(scope="module")
def env():
    env = gym.make("ClutterNav-v1", noise="none", max_episode_steps=10_000)
    yield env
    env.close()


@pytest.mark.parametrize("yaw", [0.52, 0.79, 1.31])
@pytest.mark.parametrize("before", [(0.0, 0.0), (0.5, 0.7)])
def test_zero_command_holds_position_and_heading(env, yaw, before):
    """20 s at zero command, after 1 s to come to rest: within 10 micrometres and 10 microradians."""
    moved, turned, _ = standstill_drift(env, yaw, before, seconds=20.0)
    assert moved < 1e-5
    assert turned < 1e-5


def test_driving_after_a_standstill_tracks_the_command(env):
    env.reset(seed=0, options={"scene": empty_scene(start=(-1.0, 0.0, 0.0))})
    for _ in range(20):
        env.step(STILL)
    for _ in range(40):
        obs, *_ = env.step(np.array([1.0, 0.0], dtype=np.float32))
    assert obs["velocity"][0] == pytest.approx(0.5, rel=0.02)  # max_linear_speed
    assert base_pose(env)[0][0] > -0.3
