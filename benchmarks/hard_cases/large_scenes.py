"""Large user scenes in ClutterNav-v0: first reset, the same layout again, step, physics alone and teardown.

A 30 m arena and a user scene of N small boxes and cylinders, three sizes each, on a jittered grid
(:func:`grid_scene`), loaded after one reset on a generated layout; then a 10-obstacle scene, whose reset is the
teardown. The step is the median over 300 steps of seeded random actions (an episode that ends is reset, untimed);
physics alone is the median of one step's ``stepSimulation`` calls, the robot at rest. Each N runs in a process of
its own, for as many rounds as asked; cells show the range over rounds.

    python -m benchmarks.hard_cases.large_scenes                          # N = 100, 1,000, 3,000 and 10,000
    python -m benchmarks.hard_cases.large_scenes --sizes 10000 --render   # an env that draws (render_mode="rgb_array")
"""

from __future__ import annotations

import argparse
import multiprocessing
import time

import gymnasium as gym
import numpy as np

from clutter_gym.hard_cases.large_scenes import ARENA, grid_scene
from clutter_gym.sim import pb

STEPS = 300
COLUMNS = {"first": ("first reset", "s"), "again": ("same layout again", "s"), "step": ("step", "ms"),
           "physics": ("physics alone per step", "ms"), "teardown": ("teardown (next reset)", "s")}


def measure(n: int, render: bool, queue: multiprocessing.Queue) -> None:
    """Put the figures of one N (seconds and milliseconds as :data:`COLUMNS` names them) on ``queue``."""
    scene, small = grid_scene(n), grid_scene(10)
    env = gym.make("ClutterNav-v0", arena_size=ARENA, render_mode="rgb_array" if render else None)
    env.reset(seed=0)
    out = {}
    for key in ("first", "again"):
        t = time.perf_counter()
        env.reset(seed=0, options={"scene": scene})
        out[key] = time.perf_counter() - t
    actions, steps = np.random.default_rng(0).uniform(-1, 1, (STEPS, 2)).astype(np.float32), []
    for action in actions:
        t = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(action)
        steps.append(time.perf_counter() - t)
        if terminated or truncated:
            env.reset(seed=0, options={"scene": scene})
    u = env.unwrapped
    physics = []
    for _ in range(STEPS):
        t = time.perf_counter()
        for _ in range(u.substeps):
            pb.stepSimulation(physicsClientId=u.sim.client_id)
        physics.append(time.perf_counter() - t)
    t = time.perf_counter()
    env.reset(seed=0, options={"scene": small})
    out["teardown"] = time.perf_counter() - t
    out["step"], out["physics"] = 1e3 * float(np.median(steps)), 1e3 * float(np.median(physics))
    env.close()
    queue.put(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 3000, 10000], help="obstacle counts")
    parser.add_argument("--rounds", type=int, default=2, help="processes per obstacle count")
    parser.add_argument("--render", action="store_true", help='render_mode="rgb_array": obstacles get visuals')
    args = parser.parse_args()
    context = multiprocessing.get_context("spawn")
    runs: dict[int, list[dict]] = {n: [] for n in args.sizes}
    for _ in range(args.rounds):
        for n in args.sizes:
            queue = context.Queue()
            process = context.Process(target=measure, args=(n, args.render, queue))
            process.start()
            runs[n].append(queue.get())
            process.join()
    print("| N | " + " | ".join(f"{label} ({unit})" for label, unit in COLUMNS.values()) + " |")
    print("|---" * (len(COLUMNS) + 1) + "|")
    for n, rows in runs.items():
        cells = []
        for key, (_, unit) in COLUMNS.items():
            lo, hi = min(r[key] for r in rows), max(r[key] for r in rows)
            digits = 2 if unit == "ms" or lo < 1.0 else 1
            cells.append(f"{lo:.{digits}f}" if f"{lo:.{digits}f}" == f"{hi:.{digits}f}" else
                         f"{lo:.{digits}f}–{hi:.{digits}f}")
        print(f"| {n:,} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
