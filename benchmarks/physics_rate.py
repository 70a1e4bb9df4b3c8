"""Speed against error of the physics settings: ClutterNav-v0's robot trajectory at several physics rates and
solver iteration counts, compared with a 3840 Hz / 200-iteration reference driven by the same 8 s of commands.

The error is first order in the time step (heading errors accumulate into position), so the reference is
checked against the next coarser rate, and that gap is printed with the table.

    python -m benchmarks.physics_rate
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401
from benchmarks.harness import table_header

SCENE = {"obstacles": [], "start": [-2.0, 0.0, 0.0], "goal": [2.5, 2.5]}
REFERENCE, REFERENCE_CHECK = (3840.0, 200), (1920.0, 200)
SETTINGS = ((960.0, 100), (480.0, 50), (240.0, 50), (240.0, 10), (120.0, 50), (120.0, 10), (60.0, 10))


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
    reference, _ = trajectory(*REFERENCE, actions)
    check, _ = trajectory(*REFERENCE_CHECK, actions)
    gap = 1000 * np.linalg.norm(check - reference, axis=1).max()
    print(f"reference {REFERENCE[0]:.0f} Hz / {REFERENCE[1]} iterations; {REFERENCE_CHECK[0]:.0f} Hz differs from it "
          f"by {gap:.1f} mm\n")
    length = np.linalg.norm(np.diff(reference, axis=0), axis=1).sum()
    print(f"path length {length:.2f} m\n")
    print(table_header("physics Hz", "solver iterations", "steps/s (no sensors)", "max position error over 8 s (mm)",
                       "% of path"))
    for hz, iterations in SETTINGS:
        path, rate = trajectory(hz, iterations, actions)
        error = 1000 * np.linalg.norm(path - reference, axis=1).max()
        default = " (default)" if (hz, iterations) == (120.0, 10) else ""
        print(f"| {hz:.0f}{default} | {iterations} | {rate:,.0f} | {error:.1f} | {error / 10 / length:.1f} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # --help; no options
    main()
