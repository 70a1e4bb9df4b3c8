"""Seeded clutter layouts with a reachability guarantee for the robot's footprint.

Sampling, per attempt:

1. Obstacles (boxes, cylinders, wall segments) at uniform positions and yaws until their footprints cover
   ``obstacle_density`` of the arena floor. Sizes take one of ``size_levels`` evenly spaced values per range,
   so that the body pool (``worlds/pool.py``) covers every layout with a few dozen bodies.
2. A clearance field on an occupancy grid of ``resolution`` metres: the exact signed distance from each cell
   centre to the nearest obstacle footprint or wall, evaluated only in each obstacle's window. The scene keeps it
   (``Scene.clearance_grid``) for the path-distance grid of ``worlds/path_distance.py``.
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
from dataclasses import dataclass
from functools import cached_property

import numba
import numpy as np
from scipy import ndimage

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.checks import check_fraction, check_integer
from clutter_gym.worlds.scene import Scene, polyline_distances, with_masses

MAX_DENSITY = 0.3  # beyond this a walled arena cannot reliably keep a free path for the robot
PLAIN_ATTEMPTS = 5  # attempts at unconstrained clutter before the generator keeps a corridor clear
_MAX_REFUSED_BATCHES = 50  # a corridor that leaves too little floor for the density ends the sampling early


@dataclass(frozen=True)
class ClutterSpec:
    """What a generated layout looks like.

    Attributes:
        arena_size: side of the square arena inside the walls, metres, in [2, 30].
        obstacle_density: fraction of the floor covered by obstacle footprints, in [0, 0.3].
        obstacle_height: metres; taller than the LIDAR plane so every obstacle is seen.
        box_side: (min, max) side of a box footprint, metres.
        cylinder_radius: (min, max) metres.
        wall_length: (min, max) length of a wall segment, metres (thickness ``wall_thickness``).
        shape_probs: probabilities of (box, cylinder, wall segment).
        size_levels: evenly spaced sizes per range, in [1, 10]: the number of distinct shapes, and with it the
            body pool (whose parked bodies cost physics time), grows with it.
        resolution: occupancy-grid cell size for the reachability check, metres.
        spawn_clearance: extra free space around start and goal beyond the footprint, metres.
        min_goal_distance: straight-line start-goal distance as a fraction of ``arena_size``.
        max_attempts: layouts tried before giving up.
        movable_fraction: fraction of the obstacles that are movable, in [0, 1] (a random subset; the layout is
            the same whatever the fraction).
        movable_density: kg/m^3 of movable obstacles: light enough for the robot to push, as empty cardboard
            boxes and plastic bins are.
    """

    arena_size: float = 6.0
    obstacle_density: float = 0.12
    obstacle_height: float = 0.5
    box_side: tuple[float, float] = (0.2, 0.6)
    cylinder_radius: tuple[float, float] = (0.1, 0.3)
    wall_length: tuple[float, float] = (0.8, 2.0)
    wall_thickness: float = 0.1
    shape_probs: tuple[float, float, float] = (0.45, 0.35, 0.2)
    size_levels: int = 3
    resolution: float = 0.1
    spawn_clearance: float = 0.15
    min_goal_distance: float = 0.4
    max_attempts: int = 50
    movable_fraction: float = 0.0
    movable_density: float = 30.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.arena_size) and 2.0 <= self.arena_size <= 30.0):
            raise ValueError(f"arena_size must be in [2, 30] metres, got {self.arena_size!r}")
        if not (math.isfinite(self.obstacle_density) and 0.0 <= self.obstacle_density <= MAX_DENSITY):
            raise ValueError(
                f"obstacle_density must be in [0, {MAX_DENSITY}] (fraction of the floor covered), "
                f"got {self.obstacle_density!r}"
            )
        check_integer("size_levels", self.size_levels, 1, 10)
        check_fraction("movable_obstacles", self.movable_fraction)
        if not 0.0 < self.min_goal_distance < 1.0:
            raise ValueError(
                f"min_goal_distance must be in (0, 1) (fraction of arena_size), got {self.min_goal_distance!r}"
            )

    @cached_property
    def cell_centres(self) -> np.ndarray:
        """(n,) cell-centre coordinates along one axis, metres."""
        half = 0.5 * self.arena_size
        n = int(round(self.arena_size / self.resolution))
        return -half + (np.arange(n) + 0.5) * self.arena_size / n

    @cached_property
    def size_values(self) -> dict[str, np.ndarray]:
        """The ``size_levels`` evenly spaced values (1 mm grid) of each size range, by the range's name."""
        ranges = {"box_side": self.box_side, "cylinder_radius": self.cylinder_radius, "wall_length": self.wall_length}
        return {name: np.round(np.linspace(lo, hi, self.size_levels), 3) for name, (lo, hi) in ranges.items()}

    @cached_property
    def wall_clearance(self) -> np.ndarray:
        """(n, n) distance from each cell centre to the arena walls, indexed [ix, iy]."""
        d = 0.5 * self.arena_size - np.abs(self.cell_centres)
        return np.minimum(d[:, None], d[None, :])


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


@dataclass(frozen=True)
class ClearanceGrid:
    """A layout's :func:`clearance_field`: ``values`` (n, n) on the grid of ``spec``, capped at ``cap`` metres."""

    spec: ClutterSpec
    cap: float
    values: np.ndarray


def scene_clearance(scene: Scene, spec: ClutterSpec, cap: float) -> np.ndarray:
    """``clearance_field(scene.obstacles, spec, cap)``, cut from the field the scene was sampled on when that one
    is on the same grid and capped no lower: the same numbers, as no obstacle comes nearer than ``cap`` to a cell
    it leaves out."""
    grid = scene.clearance_grid
    if grid is not None and grid.cap >= cap and grid.spec == spec:
        return np.minimum(grid.values, cap)
    return clearance_field(scene.obstacles, spec, cap)


def clearance_field(obstacles: tuple[Obstacle, ...], spec: ClutterSpec, cap: float) -> np.ndarray:
    """Distance from every cell centre to the nearest obstacle or wall, capped at ``cap`` metres.

    An obstacle only matters within ``cap`` of its enclosing circle, so each one is evaluated on the window of
    cells that reach covers. The distance is that of a rounded rectangle: a box for rounding 0, a disc for a square
    of half-side r rounded by r, so boxes and cylinders share one expression.
    """
    field = np.minimum(spec.wall_clearance, cap)
    if obstacles:
        yaw = np.array([o.yaw for o in obstacles])
        _lower_to_obstacles(
            field, spec.cell_centres, 0.5 * spec.arena_size, float(cap),
            np.array([o.position for o in obstacles], dtype=float), np.array([o.radius for o in obstacles]),
            np.array([(0.5 * o.size[0], 0.5 * o.size[1]) for o in obstacles]),
            np.array([o.radius if o.shape == "cylinder" else 0.0 for o in obstacles]), np.cos(yaw), np.sin(yaw))
    return field


@numba.njit(cache=True)
def _lower_to_obstacles(field, c, half, cap, centre, radius, half_ext, rounding, cos_y, sin_y):  # pragma: no cover
    """Lower ``field`` (n, n) to each obstacle's signed distance on the window around it (compiled)."""
    n = c.size
    res = 2.0 * half / n
    for k in range(centre.shape[0]):
        width = min(int(math.ceil(2.0 * (radius[k] + cap) / res)) + 2, n)
        lo_x = min(max(int(math.floor((centre[k, 0] - radius[k] - cap + half) / res)), 0), n - width)
        lo_y = min(max(int(math.floor((centre[k, 1] - radius[k] - cap + half) / res)), 0), n - width)
        a_x, a_y = half_ext[k, 0] - rounding[k], half_ext[k, 1] - rounding[k]
        for i in range(lo_x, lo_x + width):
            dx = c[i] - centre[k, 0]
            for j in range(lo_y, lo_y + width):
                dy = c[j] - centre[k, 1]
                qx = abs(cos_y[k] * dx + sin_y[k] * dy) - a_x
                qy = abs(-sin_y[k] * dx + cos_y[k] * dy) - a_y
                d = math.hypot(max(qx, 0.0), max(qy, 0.0)) + min(max(qx, qy), 0.0) - rounding[k]
                if d < field[i, j]:
                    field[i, j] = d


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
