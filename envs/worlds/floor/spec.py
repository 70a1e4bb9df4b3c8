"""What a generated floor layout looks like: arena size, density, obstacle size ranges and the occupancy grid."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from clutter_gym.util.checks import check_fraction, check_integer

MAX_DENSITY = 0.3  # beyond this a walled arena cannot reliably keep a free path for the robot


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
