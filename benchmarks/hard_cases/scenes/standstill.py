"""Standing still: how far a base at zero command drifts, after driving and at any heading."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.stepping import CONTROL_HZ, STILL, nav_scene, timed_steps


def base_pose(env: gym.Env) -> tuple[np.ndarray, float]:
    """The nav robot's (x, y) in metres and heading in radians."""
    state = env.unwrapped.robot.state()
    return state.position[:2].copy(), float(np.arctan2(state.rotation[1, 0], state.rotation[0, 0]))


def standstill_drift(env: gym.Env, yaw: float, before: tuple[float, float], seconds: float = 20.0
                     ) -> tuple[float, float, float]:
    """From (-1, 0) facing ``yaw``: 2 s of command ``before``, 1 s at zero command to come to rest, then
    ``seconds`` at zero command. Returns how far the base moved (m) and turned (rad) over those seconds, and env
    steps/s while holding."""
    env.reset(seed=0, options={"scene": nav_scene(start=(-1.0, 0.0, yaw))})
    for _ in range(40):
        env.step(np.array(before, dtype=np.float32))
    for _ in range(20):
        env.step(STILL)
    xy, heading = base_pose(env)
    _, rate = timed_steps(env, STILL, int(round(seconds * CONTROL_HZ)))
    xy_after, heading_after = base_pose(env)
    return float(np.linalg.norm(xy_after - xy)), abs(heading_after - heading), rate
