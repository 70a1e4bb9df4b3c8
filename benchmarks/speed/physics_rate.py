"""Speed against error of the physics settings: ClutterNav-v1's robot trajectory at several physics rates and
solver iteration counts, compared with a 3840 Hz / 200-iteration reference driven by the same 8 s of commands,
and how deep the robot sinks into a wall it is driven against at full speed for 3 s.

The trajectory error is first order in the time step (heading errors accumulate into position), so the reference
is checked against the next coarser rate, and that gap is printed with the table. The penetration is the deepest
FCL contact (``info["max_penetration"]``) over the push; a stiff, converged contact keeps it near zero.

    python -m benchmarks.speed.physics_rate
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401
from benchmarks.harness import table_header

SCENE = {"obstacles": [], "start": [-2.0, 0.0, 0.0], "goal": [2.5, 2.5]}
WALL = {"obstacles": [{"shape": "box", "size": [0.2, 2.0, 0.5], "position": [0.0, 0.0]}],
        "start": [-1.0, 0.0, 0.0], "goal": [2.5, 2.5]}
DEFAULT = (120.0, 10)
REFERENCE, REFERENCE_CHECK = (3840.0, 200), (1920.0, 200)
SETTINGS = ((960.0, 100), (480.0, 50), (240.0, 50), (240.0, 10), (120.0, 50), (120.0, 10), (60.0, 10))


def commands(n: int) -> np.ndarray:
    """Smoothly varying forward speed and turn rate (a slalom), 20 Hz."""
    k = np.arange(n)
    return np.stack([0.6 + 0.4 * np.sin(k / 10), np.cos(k / 7)], axis=1).astype(np.float32)


def trajectory(physics_hz: float, iterations: int, actions: np.ndarray) -> tuple[np.ndarray, float]:
    env = gym.make("ClutterNav-v1", physics_hz=physics_hz, solver_iterations=iterations, sensors=())
    env.reset(options={"scene": SCENE})
    robot, path, seconds = env.unwrapped.robot, [], 0.0
    for a in actions:
        t0 = time.perf_counter()
        env.step(a)
        seconds += time.perf_counter() - t0
        path.append(robot.state().position[:2].copy())
    env.close()
    return np.array(path), len(actions) / seconds


def wall_penetration_mm(physics_hz: float, iterations: int, seconds: float = 3.0) -> float:
    """Deepest FCL penetration (mm) while driving at full speed into a wall for ``seconds``."""
    env = gym.make("ClutterNav-v1", physics_hz=physics_hz, solver_iterations=iterations, sensors=(),
                   max_episode_steps=10_000)
    env.reset(options={"scene": WALL})
    deepest = 0.0
    for _ in range(int(seconds * 20)):
        _, _, _, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        deepest = max(deepest, info["max_penetration"])
    env.close()
    return 1000 * deepest


def rows() -> tuple[list[dict], float, float]:
    """Per setting: physics Hz, iterations, steps/s, max trajectory error (mm), its share of the path (%) and the
    wall penetration (mm); and the reference check's gap (mm) and the path length (m)."""
    actions = commands(160)
    reference, _ = trajectory(*REFERENCE, actions)
    check, _ = trajectory(*REFERENCE_CHECK, actions)
    gap = 1000 * np.linalg.norm(check - reference, axis=1).max()
    length = float(np.linalg.norm(np.diff(reference, axis=0), axis=1).sum())
    out = []
    for hz, iterations in SETTINGS:
        path, rate = trajectory(hz, iterations, actions)
        error = 1000 * float(np.linalg.norm(path - reference, axis=1).max())
        out.append({"hz": hz, "iterations": iterations, "rate": rate, "error_mm": error,
                    "error_pct": error / 10 / length, "penetration_mm": wall_penetration_mm(hz, iterations),
                    "default": (hz, iterations) == DEFAULT})
    return out, gap, length


def main() -> None:
    settings, gap, length = rows()
    print(f"reference {REFERENCE[0]:.0f} Hz / {REFERENCE[1]} iterations; {REFERENCE_CHECK[0]:.0f} Hz differs from it "
          f"by {gap:.1f} mm\n")
    print(f"path length {length:.2f} m\n")
    print(table_header("physics Hz", "solver iterations", "steps/s (no sensors)", "max position error over 8 s (mm)",
                       "% of path", "wall penetration at full speed (mm)"))
    for r in settings:
        default = " (default)" if r["default"] else ""
        print(f"| {r['hz']:.0f}{default} | {r['iterations']} | {r['rate']:,.0f} | {r['error_mm']:.1f} | "
              f"{r['error_pct']:.1f} | {r['penetration_mm']:.2f} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # --help; no options
    main()
