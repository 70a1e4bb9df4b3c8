"""Speed against error of the physics settings: ClutterNav-v0's robot trajectory at several physics rates and
solver iteration counts, compared with a 960 Hz / 100-iteration reference driven by the same 8 s of commands.

    python benchmarks/physics_rate.py
"""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401

SCENE = {"obstacles": [], "start": [-2.0, 0.0, 0.0], "goal": [2.5, 2.5]}
SETTINGS = ((960.0, 100), (240.0, 50), (240.0, 10), (120.0, 50), (120.0, 10), (60.0, 10))


def commands(n: int) -> np.ndarray:
    """Smoothly varying forward speed and turn rate (a slalom), 20 Hz."""
    k = np.arange(n)
    return np.stack([0.6 + 0.4 * np.sin(k / 10), np.cos(k / 7)], axis=1).astype(np.float32)


def trajectory(physics_hz: float, iterations: int, actions: np.ndarray) -> tuple[np.ndarray, float]:
    env = gym.make("ClutterNav-v0", physics_hz=physics_hz, solver_iterations=iterations, sensors=())
    env.reset(options={"scene": SCENE})
    robot, path, seconds = env.unwrapped.robot, [], 0.0
    for a in actions:
        t0 = time.perf_counter()
        env.step(a)
        seconds += time.perf_counter() - t0
        path.append(robot.state().position[:2].copy())
    env.close()
    return np.array(path), len(actions) / seconds


def main() -> None:
    actions = commands(160)
    reference, _ = trajectory(*SETTINGS[0], actions)
    print("| physics Hz | solver iterations | steps/s (no sensors) | max position error over 8 s (mm) |")
    print("|---|---|---|---|")
    for hz, iterations in SETTINGS[1:]:
        path, rate = trajectory(hz, iterations, actions)
        error = 1000 * np.linalg.norm(path - reference, axis=1).max()
        default = " (default)" if (hz, iterations) == (120.0, 10) else ""
        print(f"| {hz:.0f}{default} | {iterations} | {rate:,.0f} | {error:.1f} |")


if __name__ == "__main__":
    main()
