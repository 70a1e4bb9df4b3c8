"""Long runs: what a training run of millions of steps meets. Random actions in one env under a noise profile and
collision fidelity level, counting every non-finite value; resets of one env and make/reset/close cycles, with
resident memory and times per block.

The runs that take a ``queue`` are targets for a process of their own (resident memory is per process): they put
their result on it.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Mapping
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.memory import resident_mib
from clutter_gym.collision import FIDELITY_LEVELS
from clutter_gym.noise.profiles import PROFILE_NAMES

BLOCKS = 10  # checkpoints of the reset and cycle runs


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
    """:func:`random_steps` in one env under every noise profile and fidelity level: the cells."""
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


def growth_per(rows: list[tuple], unit: float = 1.0) -> float:
    """KB per unit of the first column over the second half of ``rows`` ((count, MiB, ...) tuples)."""
    (n0, m0, *_), (n1, m1, *_) = rows[len(rows) // 2 - 1], rows[-1]
    return (m1 - m0) * 1024 / (n1 - n0) * unit
