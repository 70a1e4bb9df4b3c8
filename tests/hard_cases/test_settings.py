"""Settings at the edge of their allowed ranges work at reset, not only at gym.make."""

from __future__ import annotations

import gymnasium as gym
import numpy as np


def test_the_largest_arena_at_the_highest_density_resets_and_steps():
    env = gym.make("ClutterNav-v0", arena_size=30.0, obstacle_density=0.3)
    for seed in (0, 1):
        obs, info = env.reset(seed=seed)
        assert len(env.unwrapped.scene.obstacles) > 1000
        assert info["min_clearance"] > 0.0
        for _ in range(10):
            obs, reward, *_ = env.step(env.action_space.sample())
            assert all(np.all(np.isfinite(v)) for v in obs.values()) and np.isfinite(reward)
    env.close()
