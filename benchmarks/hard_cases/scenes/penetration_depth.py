"""Penetration depth: the collision checker's contact depths against the signed distance of the same pair."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np


def panda_depth_errors(steps: int, seed: int = 0) -> tuple[float, int, int, float]:
    """ClutterReach-v1 (10 obstacles) driven at full joint speed in random directions for ``steps`` steps: the
    largest |contact depth - max(0, -signed distance)| of the checker's contacts after each step (m), the
    contacts and those deeper than 1 mm, and env steps/s (the extra check and signed distances excluded)."""
    env = gym.make("ClutterReach-v1", n_obstacles=10)
    checker = env.unwrapped.checker
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    worst, contacts, deep, stepping = 0.0, 0, 0, 0.0
    try:
        for _ in range(steps):
            t = time.perf_counter()
            _, _, terminated, truncated, _ = env.step(np.sign(rng.uniform(-1, 1, 7)).astype(np.float32))
            stepping += time.perf_counter() - t
            for contact in checker.check(env.unwrapped.robot.state()).contacts:
                i = next(k for k in checker.search.moving if checker.model.shapes[k].link == contact.link)
                worst = max(worst, abs(contact.depth - max(0.0, -checker.pair_distance(i, contact.obstacle))))
                contacts += 1
                deep += contact.depth > 1e-3
            if terminated or truncated:
                env.reset()
    finally:
        env.close()
    return worst, contacts, deep, steps / stepping
