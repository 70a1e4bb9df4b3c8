"""Seeded table layouts: a shelf, clutter kept clear of the start pose's arm, a start pose around the ready pose,
and a target within the arm's reach that clears every obstacle (in a shelf compartment or above the table)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.sampling import polyline_distances, with_masses
from clutter_gym.worlds.table.scene import ReachScene, point_clearance
from clutter_gym.worlds.table.spec import TableSpec

ARM_KEEP_OUT = 0.15  # generated obstacles keep this far from the vertical plane of the start pose's arm, metres


def shelf_parts(centre: tuple[float, float], yaw: float, width: float = 0.4, depth: float = 0.25,
                height: float = 0.45, board: float = 0.2, thick: float = 0.02) -> tuple[Obstacle, ...]:
    """A shelf open towards -x of its own frame (rotated by ``yaw``), as five boxes."""
    c, s = math.cos(yaw), math.sin(yaw)

    def at(dx: float, dy: float) -> tuple[float, float]:
        return (centre[0] + c * dx - s * dy, centre[1] + s * dx + c * dy)

    half_d, half_w = 0.5 * depth, 0.5 * width
    return (
        Obstacle("box", (thick, width, height), at(half_d - 0.5 * thick, 0.0), yaw),
        Obstacle("box", (depth, thick, height), at(0.0, half_w - 0.5 * thick), yaw),
        Obstacle("box", (depth, thick, height), at(0.0, -half_w + 0.5 * thick), yaw),
        Obstacle("box", (depth - thick, width - 2 * thick, thick), at(-0.5 * thick, 0.0), yaw, board),
        Obstacle("box", (depth, width, thick), at(0.0, 0.0), yaw, height),
    )


def sample_reach_scene(rng: np.random.Generator, spec: TableSpec, ready: Sequence[float],
                       shoulder: Sequence[float], reach: float) -> ReachScene:
    """A seeded layout: shelf, clutter clear of the start pose's arm, start pose and a target within ``reach``
    metres of ``shoulder`` (the arm's: its model's ``shoulder`` and ``reach``)."""
    obstacles: list[Obstacle] = []
    footprints: list[tuple[np.ndarray, float]] = []  # (centre, radius) of every placed footprint
    arm = np.array([[0.0, 0.0], [0.45, 0.0]])
    shelf_compartments: list[tuple[np.ndarray, float]] = []
    if spec.shelf:
        angle = rng.uniform(-1.1, 1.1)
        angle += math.copysign(0.35, angle)  # keep the shelf off the arm's start plane
        r = rng.uniform(0.55, 0.7)
        centre = (r * math.cos(angle), r * math.sin(angle))
        parts = shelf_parts(centre, angle)
        obstacles.extend(parts)
        footprints.append((np.array(centre), 0.25))
        for low, high in ((0.0, 0.2), (0.22, 0.45)):  # two compartments: (centre, height)
            inner = np.array(centre) - 0.02 * np.array([math.cos(angle), math.sin(angle)])
            shelf_compartments.append((np.array([*inner, 0.5 * (low + high)]), high - low))
    tries = 0
    while len(obstacles) < spec.n_obstacles + (5 if spec.shelf else 0) and tries < 200:
        tries += 1
        r, angle = rng.uniform(0.3, 0.75), rng.uniform(-2.0, 2.0)
        xy = np.array([r * math.cos(angle), r * math.sin(angle)])
        if rng.uniform() < 0.5:
            size = (float(rng.choice([0.05, 0.08, 0.12])), float(rng.choice([0.05, 0.08, 0.12])),
                    float(rng.choice([0.08, 0.15, 0.25, 0.35])))
            candidate = Obstacle("box", size, (float(xy[0]), float(xy[1])), float(rng.uniform(-math.pi, math.pi)))
        else:
            radius = float(rng.choice([0.03, 0.045, 0.06]))
            height = float(rng.choice([0.1, 0.2, 0.3]))
            candidate = Obstacle("cylinder", (2 * radius, 2 * radius, height), (float(xy[0]), float(xy[1])))
        extent = candidate.radius
        if polyline_distances(xy[None], arm)[0] < extent + ARM_KEEP_OUT:
            continue
        if any(np.linalg.norm(xy - c) < extent + rc + 0.02 for c, rc in footprints):
            continue
        obstacles.append(candidate)
        footprints.append((xy, extent))
    start = tuple(float(v) for v in np.asarray(ready) + rng.uniform(-spec.start_noise, spec.start_noise,
                                                                    size=len(ready)))
    target = _sample_target(rng, spec, tuple(obstacles), shelf_compartments, np.asarray(shoulder), reach)
    clutter = range(5 if spec.shelf else 0, len(obstacles))  # the shelf is furniture: it stays put
    return ReachScene(with_masses(obstacles, clutter, spec.movable_fraction, spec.movable_density), start, target)


def _sample_target(rng: np.random.Generator, spec: TableSpec, obstacles: tuple[Obstacle, ...],
                   compartments: list[tuple[np.ndarray, float]], shoulder: np.ndarray,
                   reach: float) -> tuple[float, float, float]:
    if compartments and rng.uniform() < spec.shelf_target_probability:
        centre, _ = compartments[int(rng.integers(len(compartments)))]
        return tuple(float(v) for v in centre)
    for _ in range(1000):
        p = np.array([rng.uniform(0.15, 0.75), rng.uniform(-0.6, 0.6), rng.uniform(0.05, 0.55)])
        if np.linalg.norm(p - shoulder) > reach or np.hypot(p[0], p[1]) < 0.3:
            continue
        if point_clearance(p, obstacles) >= spec.target_clearance:
            return tuple(float(v) for v in p)
    raise RuntimeError("no free target point found in 1000 draws; lower n_obstacles")
