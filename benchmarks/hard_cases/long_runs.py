"""Long runs: what a training run of millions of steps meets, in three parts.

* ``steps``: random actions in every env under every noise profile and collision fidelity level (one env per cell,
  made and closed in turn; one process per env id). Every observation, reward and info value must be finite; the
  process's resident memory is read after each cell.
* ``resets``: one ClutterNav-v0 env reset over and over; reset time and resident memory per block of resets.
* ``cycles``: ``gym.make`` + reset + ``close`` over and over, per env id; resident memory.

    python -m benchmarks.hard_cases.long_runs    # 10^6 steps, 100,000 resets, 1,000 cycles per env
    python -m benchmarks.hard_cases.long_runs --steps 20000 --resets 2000 --cycles 50 --parts steps resets

Growth is taken over the second half of each run, after warm-up allocations. Steps/s are measured while the
machine may be shared: compare them within one run only.
"""

from __future__ import annotations

import argparse
import multiprocessing
import queue as queues
import time
from collections.abc import Mapping
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.hard_cases.memory import resident_mib
from clutter_gym import ENV_IDS
from clutter_gym.collision import FIDELITY_LEVELS
from clutter_gym.noise.profiles import PROFILE_NAMES

BLOCKS = 10  # checkpoints of the reset and cycle runs
PARTS = ("steps", "resets", "cycles")


@dataclass(frozen=True)
class Cell:
    """One (env, noise profile, fidelity level) stretch of random steps."""

    env_id: str
    profile: str
    level: str
    steps: int
    episodes: int
    collisions: int  # steps with a positive cost
    nonfinite: int  # steps with a NaN or Inf anywhere in observation, reward or info
    steps_per_s: float
    resident_mib: float  # after the cell's env was closed


def count_nonfinite(value: object) -> int:
    """Non-finite numbers anywhere in ``value`` (nested dicts, sequences, arrays, scalars); other values count 0."""
    if isinstance(value, Mapping):
        return sum(count_nonfinite(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return sum(count_nonfinite(v) for v in value)
    if isinstance(value, (np.ndarray, np.generic, float, int)) and not isinstance(value, bool):
        array = np.asarray(value)
        return int(array.size - np.count_nonzero(np.isfinite(array))) if array.dtype.kind in "fc" else 0
    return 0


def random_steps(env_id: str, profile: str, level: str, steps: int, seed: int) -> Cell:
    """``steps`` uniform random actions in one env, resetting when an episode ends."""
    env = gym.make(env_id, noise=profile, collision_fidelity=level)
    rng = np.random.default_rng(seed)
    shape = env.action_space.shape
    obs, info = env.reset(seed=seed)
    bad = int(count_nonfinite(obs) + count_nonfinite(info) > 0)
    episodes, collisions = 1, 0
    t0 = time.perf_counter()
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1.0, 1.0, shape))
        bad += count_nonfinite(obs) + count_nonfinite(reward) + count_nonfinite(info) > 0
        collisions += info["cost"] > 0
        if terminated or truncated:
            obs, info = env.reset()
            bad += count_nonfinite(obs) + count_nonfinite(info) > 0
            episodes += 1
    elapsed = time.perf_counter() - t0
    env.close()
    return Cell(env_id, profile, level, steps, episodes, int(collisions), int(bad), steps / elapsed, resident_mib())


def steps_run(env_id: str, steps_per_cell: int, queue: multiprocessing.Queue) -> None:
    cells = [random_steps(env_id, profile, level, steps_per_cell, seed)
             for seed, (profile, level) in enumerate((p, lv) for p in PROFILE_NAMES for lv in FIDELITY_LEVELS)]
    queue.put(cells)


def resets_run(env_id: str, resets: int, queue: multiprocessing.Queue) -> None:
    """(resets so far, resident MiB, median reset ms in the block) per block."""
    env = gym.make(env_id)
    env.reset(seed=0)
    rows, block = [], max(1, resets // BLOCKS)
    times = []
    for i in range(1, resets + 1):
        t0 = time.perf_counter()
        env.reset()
        times.append(time.perf_counter() - t0)
        if i % block == 0:
            rows.append((i, resident_mib(), 1e3 * float(np.median(times))))
            times = []
    env.close()
    queue.put(rows)


def cycles_run(env_id: str, cycles: int, queue: multiprocessing.Queue) -> None:
    """(cycles so far, resident MiB, median make+reset+close ms in the block) per block."""
    rows, block, times = [], max(1, cycles // BLOCKS), []
    start = None
    for i in range(1, cycles + 1):
        t0 = time.perf_counter()
        env = gym.make(env_id)
        env.reset(seed=i)
        env.close()
        times.append(time.perf_counter() - t0)
        if start is None:
            start = resident_mib()  # after the first cycle: imports and caches are in
        if i % block == 0:
            rows.append((i, resident_mib(), 1e3 * float(np.median(times))))
            times = []
    queue.put((start, rows))


def in_processes(target, argsets: list[tuple], jobs: int) -> list:
    """``target(*args, queue)`` for each of ``argsets``, each in a fresh spawned process, ``jobs`` at a time;
    returns what each put on its queue, in order."""
    context = multiprocessing.get_context("spawn")
    results: list = [None] * len(argsets)
    for first in range(0, len(argsets), jobs):
        running = []
        for k in range(first, min(first + jobs, len(argsets))):
            queue = context.Queue()
            process = context.Process(target=target, args=(*argsets[k], queue))
            process.start()
            running.append((k, process, queue))
        for k, process, queue in running:
            results[k] = _result(process, queue)
            process.join()
    return results


def _result(process: multiprocessing.Process, queue: multiprocessing.Queue) -> object:
    """What ``process`` puts on ``queue``; raises if it dies first (its traceback is on stderr)."""
    while True:
        try:
            return queue.get(timeout=5.0)
        except queues.Empty:
            if not process.is_alive():
                raise RuntimeError(f"{process.name} ended with exit code {process.exitcode} and no result") from None


def growth_per(rows: list[tuple], unit: float = 1.0) -> float:
    """KB per unit of the first column over the second half of ``rows`` ((count, MiB, ...) tuples)."""
    (n0, m0, *_), (n1, m1, *_) = rows[len(rows) // 2 - 1], rows[-1]
    return (m1 - m0) * 1024 / (n1 - n0) * unit


def print_steps(cells_per_env: list[list[Cell]], seconds: float) -> None:
    cells = [c for env_cells in cells_per_env for c in env_cells]
    print(f"## Random steps: {sum(c.steps for c in cells):,} steps in {seconds / 60:.1f} min\n")
    print("| env | profile | fidelity | steps | episodes | steps with cost | non-finite steps | steps/s | RSS MiB |")
    print("|---|---|---|---|---|---|---|---|---|")
    for c in cells:
        print(f"| {c.env_id} | {c.profile} | {c.level} | {c.steps:,} | {c.episodes} | {c.collisions} | {c.nonfinite} "
              f"| {c.steps_per_s:.0f} | {c.resident_mib:.1f} |")
    for env_cells in cells_per_env:
        half = len(env_cells) // 2
        print(f"\n{env_cells[0].env_id}: resident memory {env_cells[0].resident_mib:.1f} MiB after the first cell, "
              f"{env_cells[half - 1].resident_mib:.1f} at half, {env_cells[-1].resident_mib:.1f} at the end "
              f"({len(env_cells)} envs made and closed)")
    print(f"\nnon-finite steps in all: {sum(c.nonfinite for c in cells)}\n")


def print_blocks(title: str, rows: list[tuple], what: str, start: float | None = None) -> None:
    print(f"## {title}\n")
    print(f"| {what} | RSS MiB | median ms in the block |")
    print("|---|---|---|")
    for n, mib, ms in rows:
        print(f"| {n:,} | {mib:.1f} | {ms:.2f} |")
    tail = f"; {rows[-1][1] - start:+.1f} MiB since the first" if start is not None else ""
    print(f"\nsecond half: {growth_per(rows):+.3f} KB per {what}; last block's median over the first's: "
          f"{rows[-1][2] / rows[0][2]:.2f}x{tail}\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000, help="random steps in all, over every cell")
    parser.add_argument("--resets", type=int, default=100_000, help="resets of one ClutterNav-v0 env")
    parser.add_argument("--cycles", type=int, default=1_000, help="make/reset/close cycles per env id")
    parser.add_argument("--parts", nargs="+", choices=PARTS, default=PARTS)
    parser.add_argument("--jobs", type=int, default=2, help="processes at a time")
    args = parser.parse_args()
    n_cells = len(ENV_IDS) * len(PROFILE_NAMES) * len(FIDELITY_LEVELS)
    for name, value, least in (("--steps", args.steps, n_cells), ("--resets", args.resets, BLOCKS),
                               ("--cycles", args.cycles, BLOCKS)):
        if value < least:
            parser.error(f"{name} must be at least {least}, got {value}")
    if "steps" in args.parts:
        t0 = time.perf_counter()
        cells = in_processes(steps_run, [(env_id, args.steps // n_cells) for env_id in ENV_IDS], args.jobs)
        print_steps(cells, time.perf_counter() - t0)
    if "resets" in args.parts:
        (rows,) = in_processes(resets_run, [("ClutterNav-v0", args.resets)], 1)
        print_blocks(f"{args.resets:,} resets of one ClutterNav-v0 env", rows, "reset")
    if "cycles" in args.parts:
        for env_id, (start, rows) in zip(ENV_IDS, in_processes(cycles_run, [(e, args.cycles) for e in ENV_IDS],
                                                                args.jobs)):
            print_blocks(f"{args.cycles:,} make/reset/close cycles of {env_id}", rows, "cycle", start)


if __name__ == "__main__":
    main()
