"""Long runs: what a training run of millions of steps meets, in three parts.

* ``steps``: random actions in every env under every noise profile and collision fidelity level (one env per cell,
  made and closed in turn; one process per env id). Every observation, reward and info value must be finite; the
  process's resident memory is read after each cell.
* ``resets``: one ClutterNav-v1 env reset over and over; reset time and resident memory per block of resets.
* ``cycles``: ``gym.make`` + reset + ``close`` over and over, per env id; resident memory.

    python -m benchmarks.hard_cases.long_runs    # 10^6 steps, 100,000 resets, 1,000 cycles per env
    python -m benchmarks.hard_cases.long_runs --steps 20000 --resets 2000 --cycles 50 --parts steps resets

Each part runs :mod:`benchmarks.hard_cases.scenes.long_runs` (whose short versions tests/hard_cases/test_long_runs.py
checks) in processes of its own. Growth is taken over the second half of each run, after warm-up allocations.
Steps/s are measured while the machine may be shared: compare them within one run only.
"""

from __future__ import annotations

import argparse
import multiprocessing
import queue as queues
import time

from benchmarks.hard_cases.scenes.long_runs import BLOCKS, Cell, cycles_run, growth_per, resets_run, steps_run
from clutter_gym import ENV_IDS
from clutter_gym.collision import FIDELITY_LEVELS
from clutter_gym.noise.profiles import PROFILE_NAMES

PARTS = ("steps", "resets", "cycles")


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
    parser.add_argument("--resets", type=int, default=100_000, help="resets of one ClutterNav-v1 env")
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
        (rows,) = in_processes(resets_run, [("ClutterNav-v1", args.resets)], 1)
        print_blocks(f"{args.resets:,} resets of one ClutterNav-v1 env", rows, "reset")
    if "cycles" in args.parts:
        for env_id, (start, rows) in zip(ENV_IDS, in_processes(cycles_run, [(e, args.cycles) for e in ENV_IDS],
                                                                args.jobs)):
            print_blocks(f"{args.cycles:,} make/reset/close cycles of {env_id}", rows, "cycle", start)


if __name__ == "__main__":
    main()
