"""Memory while an env stays open: the process's resident memory, and scenes of obstacle sizes never seen before
(each one a shape pybullet cannot free)."""

from __future__ import annotations

import os

import numpy as np


def resident_mib() -> float:
    """Resident memory of this process in MiB (Linux: /proc/self/statm)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def new_sizes_scene(rng: np.random.Generator) -> dict:
    """A ClutterNav scene of five cylinders of sizes no earlier scene had (in the reset-options format)."""
    obstacles = [{"shape": "cylinder", "radius": float(rng.uniform(0.1, 0.3)), "height": 0.5,
                  "position": [float(rng.uniform(0.5, 1.5)), float(rng.uniform(-1.5, 1.5))]} for _ in range(5)]
    return {"obstacles": obstacles, "start": [-2.0, 0.0, 0.0], "goal": [2.5, 0.0]}
