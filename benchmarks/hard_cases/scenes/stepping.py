"""What the hard cases that step an env share: a ClutterNav scene in the reset-options format, timed steps, and
the nav robot's still and full-ahead commands."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np

CONTROL_HZ = 20.0  # ClutterNav-v1 and ClutterReach-v1 control steps per second
STILL = np.zeros(2, dtype=np.float32)
FULL_AHEAD = np.array([1.0, 0.0], dtype=np.float32)


def nav_scene(start=(0.0, 0.0, 0.0), goal=(2.5, 2.5), obstacles=()) -> dict:
    """A ClutterNav scene in the reset-options format: start (x, y, yaw), goal (x, y), obstacles as dicts."""
    return {"obstacles": list(obstacles), "start": list(start), "goal": list(goal)}


def timed_steps(env: gym.Env, action: np.ndarray, n: int) -> tuple[list[tuple], float]:
    """``n`` steps of ``action``: each step's (obs, reward, terminated, truncated, info), and env steps/s."""
    out, began = [], time.perf_counter()
    for _ in range(n):
        out.append(env.step(action))
    return out, n / (time.perf_counter() - began)
