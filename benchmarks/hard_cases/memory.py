"""Memory while an env stays open: resident memory across many resets, for the runs that used to grow.

Each run is its own process (resident memory is per process, and one run's heap must not hide another's):
ClutterReach-v1 on generated layouts, ClutterNav-v1 on generated layouts, and ClutterNav-v1 on user scenes with
five cylinders of new sizes each reset (every one a shape pybullet cannot free). It prints resident memory at
checkpoints and the growth per reset over the second half of the run, when warm-up allocations are done.

    python -m benchmarks.hard_cases.memory --resets 20000
"""

from __future__ import annotations

import argparse
import multiprocessing
import time

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.memory import new_sizes_scene, resident_mib

RUNS = {
    "ClutterReach-v1, generated layouts": ("ClutterReach-v1", False),
    "ClutterNav-v1, generated layouts": ("ClutterNav-v1", False),
    "ClutterNav-v1, 5 new cylinder sizes per user scene": ("ClutterNav-v1", True),
}
CHECKPOINTS = 10


def run(env_id: str, user_scenes: bool, resets: int, queue: multiprocessing.Queue) -> None:
    env = gym.make(env_id)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    rows, t0 = [], time.perf_counter()
    for i in range(1, resets + 1):
        env.reset(options={"scene": new_sizes_scene(rng)} if user_scenes else None)
        if i % (resets // CHECKPOINTS) == 0:
            rows.append((i, resident_mib(), time.perf_counter() - t0))
    env.close()
    queue.put(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resets", type=int, default=20_000, help="resets per run (at least 10)")
    args = parser.parse_args()
    if args.resets < CHECKPOINTS:
        parser.error(f"--resets must be at least {CHECKPOINTS}")
    context = multiprocessing.get_context("spawn")
    print(f"{args.resets} resets per run; resident memory (MiB) after the given resets\n")
    for label, (env_id, user_scenes) in RUNS.items():
        queue = context.Queue()
        process = context.Process(target=run, args=(env_id, user_scenes, args.resets, queue))
        process.start()
        rows = queue.get()
        process.join()
        checkpoints = ", ".join(f"{i}: {mib:.1f}" for i, mib, _ in rows)
        (i_half, half, _), (i_end, end, _) = rows[len(rows) // 2 - 1], rows[-1]
        growth = (end - half) * 1024 / (i_end - i_half)
        print(f"{label}\n  {checkpoints}\n  second half: {growth:+.2f} KB per reset; {rows[-1][2]:.0f} s\n")


if __name__ == "__main__":
    main()
