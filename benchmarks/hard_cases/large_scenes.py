"""Large user scenes in ClutterNav-v1: first reset, the same layout again, step, physics alone and teardown.

A 30 m arena and a user scene of N small boxes and cylinders, three sizes each, on a jittered grid
(:func:`grid_scene`), loaded after one reset on a generated layout; then a 10-obstacle scene, whose reset is the
teardown. The step is the median over 300 steps of seeded random actions (an episode that ends is reset, untimed);
"x smallest" is that step over the smallest N's step of the same rounds (the issue's target: 10,000 obstacles at most
3x 100). Physics alone is the median of one step's ``stepSimulation`` calls, the robot at rest where the run left it
(in contact or not: it moves with the run). "bodies" counts the obstacles that were bodies at the end. Each N runs in
a process of its own, with the near field (only the obstacles near the robot are bodies: ``worlds/near_field.py``)
and, with ``--full-world``, also without it, alternating, for as many rounds as asked; cells show the range over
rounds.

    python -m benchmarks.hard_cases.large_scenes                          # N = 100, 1,000, 3,000 and 10,000
    python -m benchmarks.hard_cases.large_scenes --sizes 100 10000 --full-world --rounds 3
    python -m benchmarks.hard_cases.large_scenes --sizes 10000 --render   # an env that draws (render_mode="rgb_array")
"""

from __future__ import annotations

import argparse
import multiprocessing
import time

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.large_scenes import ARENA, grid_scene
from clutter_gym.sim import pb

STEPS = 300
COLUMNS = {"first": ("first reset", "s"), "again": ("same layout again", "s"), "step": ("step", "ms"),
           "ratio": ("x smallest", ""), "physics": ("physics alone per step", "ms"), "bodies": ("bodies", ""),
           "teardown": ("teardown (next reset)", "s")}


def measure(n: int, render: bool, queue: multiprocessing.Queue, near_field: bool = True) -> None:
    """Put the figures of one N (seconds and milliseconds as :data:`COLUMNS` names them) on ``queue``."""
    scene, small = grid_scene(n), grid_scene(10)
    env = gym.make("ClutterNav-v1", arena_size=ARENA, render_mode="rgb_array" if render else None)
    env.unwrapped.arena.near_field = near_field and env.unwrapped.arena.near_field
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
    out["bodies"] = len(u.arena._pool.placed)
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
    parser.add_argument("--full-world", action="store_true", help="also every obstacle a body (no near field)")
    args = parser.parse_args()
    context = multiprocessing.get_context("spawn")
    modes = [True, False] if args.full_world else [True]
    runs: dict[tuple[bool, int], list[dict]] = {(m, n): [] for m in modes for n in args.sizes}
    for _ in range(args.rounds):
        for n in args.sizes:
            for near in modes:
                queue = context.Queue()
                process = context.Process(target=measure, args=(n, args.render, queue, near))
                process.start()
                runs[near, n].append(queue.get())
                process.join()
    smallest = min(args.sizes)
    for (near, n), rows in runs.items():
        for row, base in zip(rows, runs[near, smallest]):
            row["ratio"] = row["step"] / base["step"]
    print("| N | " + " | ".join(f"{label} ({unit})" if unit else label for label, unit in COLUMNS.values()) + " |")
    print("|---" * (len(COLUMNS) + 1) + "|")
    for (near, n), rows in runs.items():
        cells = []
        for key, (_, unit) in COLUMNS.items():
            lo, hi = min(r[key] for r in rows), max(r[key] for r in rows)
            digits = 0 if key == "bodies" else 2 if unit in ("ms", "") or lo < 1.0 else 1
            cells.append(f"{lo:.{digits}f}" if f"{lo:.{digits}f}" == f"{hi:.{digits}f}" else
                         f"{lo:.{digits}f}–{hi:.{digits}f}")
        label = f"{n:,}" if near else f"{n:,}, every obstacle a body"
        print(f"| {label} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
