"""Helpers the seeded layouts of several worlds share: which obstacles are movable, and distances to a polyline
(the corridor a generator keeps clear, the arm's start plane on the table)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.parsing import MASS_RANGE


def with_masses(obstacles: Sequence[Obstacle], eligible: Sequence[int], fraction: float,
                density: float) -> tuple[Obstacle, ...]:
    """``obstacles`` with the first ``round(fraction * len(eligible))`` of the ``eligible`` ones (indices) made
    movable at ``density`` kg/m^3 (each mass clipped to :data:`MASS_RANGE`).

    A generated layout lists its obstacles in random order, so the first ones are a random subset, and the
    layout itself is the same whatever the fraction: no random number is drawn here.
    """
    chosen = eligible[:round(fraction * len(eligible))]
    if not chosen:
        return tuple(obstacles)
    out = list(obstacles)
    for i in chosen:
        mass = float(min(max(density * out[i].volume, MASS_RANGE[0]), MASS_RANGE[1]))
        out[i] = dataclasses.replace(out[i], mass=mass)
    return tuple(out)


def polyline_distances(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """(n,) distance from each of ``points`` (n, 2) to the polyline through ``polyline`` (k, 2), k >= 2."""
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    t = np.einsum("nsd,sd->ns", points[:, None, :] - a[None], ab) / np.maximum(np.einsum("sd,sd->s", ab, ab), 1e-12)
    nearest = a[None] + np.clip(t, 0.0, 1.0)[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - nearest, axis=2).min(axis=1)
