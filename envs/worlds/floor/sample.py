"""Seeded clutter layouts with a reachability guarantee for the robot's footprint.

Sampling, per attempt:

1. Obstacles (boxes, cylinders, wall segments) at uniform positions and yaws until their footprints cover
   ``obstacle_density`` of the arena floor. Sizes take one of ``size_levels`` evenly spaced values per range,
   so that the body pool (``worlds/pool.py``) covers every layout with a few dozen bodies.
2. The clearance field of ``worlds/floor/grid.py`` on an occupancy grid of ``resolution`` metres: the exact signed
   distance from each cell centre to the nearest obstacle footprint or wall. The scene keeps it
   (``Scene.clearance_grid``) for the path distance of ``worlds/floor/path.py``.
3. A cell is *free* when its clearance exceeds ``r + resolution / 2`` (r = footprint radius). The distance is
   1-Lipschitz and every point of a segment between 4-neighbour centres lies within ``resolution / 2`` of one
   of them, so a 4-connected chain of free cells is a collision-free path for the disc: same free component
   means reachable.
4. Start and goal come from free cells with the extra ``spawn_clearance``, in one component and at least
   ``min_goal_distance`` apart. No such pair: a new attempt.

Dense clutter in a large arena leaves no free component that spans it (at density 0.3 in a 30 m arena the
largest one holds a few percent of the free cells), so after ``PLAIN_ATTEMPTS`` failed attempts the generator
keeps a corridor clear: it draws start, goal and one waypoint first and refuses obstacles whose enclosing circle
comes within ``r + spawn_clearance + resolution`` of the polyline through them. Every cell the polyline crosses is
then free, the steps above find start and goal in one component, and the density is still met elsewhere.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.floor.grid import ClearanceGrid, clearance_field
from clutter_gym.worlds.floor.scene import Scene
from clutter_gym.worlds.floor.spec import ClutterSpec
from clutter_gym.worlds.sampling import polyline_distances, with_masses

PLAIN_ATTEMPTS = 5  # attempts at unconstrained clutter before the generator keeps a corridor clear
_MAX_REFUSED_BATCHES = 50  # a corridor that leaves too little floor for the density ends the sampling early


def _level_values(rng: np.random.Generator, choices: np.ndarray, n: int) -> np.ndarray:
    """``n`` values drawn uniformly from ``choices``."""
    return choices[rng.integers(0, len(choices), size=n)]


def _corridor(rng: np.random.Generator, spec: ClutterSpec, keep: float) -> np.ndarray | None:
    """(3, 2) start, waypoint and goal, each ``keep`` inside the walls, start and goal ``min_goal_distance``
    apart; None when the arena is too small for such a pair."""
    half = 0.5 * spec.arena_size - keep
    if half <= 0:
        return None
    ends = rng.uniform(-half, half, size=(64, 2, 2))
    far = np.flatnonzero(np.hypot(*(ends[:, 0] - ends[:, 1]).T) >= spec.min_goal_distance * spec.arena_size)
    if far.size == 0:
        return None
    start, goal = ends[far[0]]
    return np.array([start, rng.uniform(-half, half, size=2), goal])


def _sample_obstacles(
    rng: np.random.Generator, spec: ClutterSpec, corridor: np.ndarray | None = None, keep: float = 0.0
) -> tuple[Obstacle, ...]:
    """Obstacles drawn in batches until their footprints cover ``obstacle_density`` of the floor; with a
    ``corridor`` polyline, none whose enclosing circle comes within ``keep`` metres of it."""
    target = spec.obstacle_density * spec.arena_size**2
    obstacles: list[Obstacle] = []
    covered, half, h = 0.0, 0.5 * spec.arena_size, spec.obstacle_height
    batch, refused = 32, 0
    while covered < target and refused < _MAX_REFUSED_BATCHES:
        kind = rng.choice(3, size=batch, p=spec.shape_probs)
        sizes = spec.size_values
        side_a, side_b = _level_values(rng, sizes["box_side"], batch), _level_values(rng, sizes["box_side"], batch)
        radius = _level_values(rng, sizes["cylinder_radius"], batch)
        length = _level_values(rng, sizes["wall_length"], batch)
        yaw = rng.uniform(-math.pi, math.pi, size=batch)
        xy = rng.uniform(-half, half, size=(batch, 2))
        gap = polyline_distances(xy, corridor) - keep if corridor is not None else np.full(batch, np.inf)
        placed = len(obstacles)
        for i in range(batch):
            if covered >= target:
                break
            if kind[i] == 0:
                o = Obstacle("box", (max(side_a[i], side_b[i]), min(side_a[i], side_b[i]), h), (xy[i, 0], xy[i, 1]),
                             float(yaw[i]))
            elif kind[i] == 1:
                o = Obstacle("cylinder", (2 * radius[i], 2 * radius[i], h), (xy[i, 0], xy[i, 1]), 0.0)
            else:
                o = Obstacle("box", (length[i], spec.wall_thickness, h), (xy[i, 0], xy[i, 1]), float(yaw[i]))
            if o.radius > gap[i]:  # its enclosing circle reaches into the corridor
                continue
            obstacles.append(o)
            covered += o.area
        refused = refused + 1 if len(obstacles) == placed else 0
    return tuple(obstacles)


def _cell(point: np.ndarray, spec: ClutterSpec) -> int:
    """Flat index of the grid cell holding ``point`` (x, y)."""
    n = len(spec.cell_centres)
    ix, iy = np.clip(((point + 0.5 * spec.arena_size) * n / spec.arena_size).astype(int), 0, n - 1)
    return int(ix * n + iy)


def sample_scene(rng: np.random.Generator, spec: ClutterSpec, robot_radius: float) -> Scene:
    """A random layout whose goal is reachable for a disc of ``robot_radius`` (see the module docstring).

    Raises:
        RuntimeError: no valid layout in ``spec.max_attempts`` tries (density too high for the robot).
    """
    free_margin = robot_radius + 0.5 * spec.resolution
    spawn_margin = robot_radius + spec.spawn_clearance
    c = spec.cell_centres
    cap = spawn_margin + spec.resolution
    for attempt in range(spec.max_attempts):
        corridor = _corridor(rng, spec, cap) if attempt >= PLAIN_ATTEMPTS else None
        obstacles = _sample_obstacles(rng, spec, corridor, cap)
        field = clearance_field(obstacles, spec, cap)
        labels, _ = ndimage.label(field > free_margin)
        spawn = np.flatnonzero((field > spawn_margin).ravel())
        if spawn.size < 2:
            continue
        start_cell = int(rng.choice(spawn)) if corridor is None else _cell(corridor[0], spec)
        component = labels.ravel()[start_cell]
        ix, iy = np.unravel_index(spawn, field.shape)
        sx, sy = c[start_cell // len(c)], c[start_cell % len(c)]
        far = np.hypot(c[ix] - sx, c[iy] - sy) >= spec.min_goal_distance * spec.arena_size
        goals = spawn[far & (labels.ravel()[spawn] == component)]
        if corridor is not None:  # the far end of the corridor when its cell qualifies, as it does by construction
            end = _cell(corridor[2], spec)
            goals = goals[goals == end] if np.any(goals == end) else goals
        if goals.size == 0 or field.ravel()[start_cell] <= spawn_margin:
            continue
        goal_cell = int(rng.choice(goals))
        gx, gy = c[goal_cell // len(c)], c[goal_cell % len(c)]
        yaw = float(rng.uniform(-math.pi, math.pi))
        field.flags.writeable = False
        obstacles = with_masses(obstacles, range(len(obstacles)), spec.movable_fraction, spec.movable_density)
        return Scene(obstacles, (float(sx), float(sy), yaw), (float(gx), float(gy)), ClearanceGrid(spec, cap, field))
    raise RuntimeError(
        f"no layout with a reachable goal in {spec.max_attempts} attempts at obstacle_density="
        f"{spec.obstacle_density} in a {spec.arena_size} m arena; lower the density or enlarge the arena"
    )
