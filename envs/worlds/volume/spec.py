"""What a generated ClutterFly volume looks like: sizes, density, obstacle size ranges and the occupancy grid.

Frame: world z up, metres. The volume is the box [-sx/2, sx/2] x [-sy/2, sy/2] x [0, sz] (``size`` = (sx, sy, sz)),
the floor at z = 0, walled on four sides, and closed by a ceiling at z = sz when ``ceiling`` is on. Without one the
top of the volume still bounds the occupancy grid, so generated paths stay inside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from clutter_gym.util.checks import check_integer, is_number
from clutter_gym.worlds.parsing import MAX_OBSTACLE_HEIGHT

SIZE_RANGE = ((2.0, 30.0), (2.0, 30.0), (1.0, MAX_OBSTACLE_HEIGHT))  # metres per axis; poles span the height
MAX_DENSITY = 0.25  # fraction of the volume; beyond it few layouts keep a path for a drone-sized sphere
MAX_CELLS = 4_000_000  # occupancy-grid cells: the grid's arrays stay in the tens of megabytes
SHAPES = ("pole", "box", "beam", "wall")  # the kinds of obstacle, in the order of ``shape_probs``


def _number(name: str, value: Any, lo: float, hi: float) -> float:
    if not (is_number(value) and math.isfinite(value) and lo <= value <= hi):
        raise ValueError(f"{name} must be a number in [{lo:g}, {hi:g}], got {value!r}")
    return float(value)


def _numbers(name: str, value: Any, n: int, what: str) -> tuple[float, ...]:
    """``value`` as a tuple of ``n`` finite floats (a sequence or 1-D array); else a ValueError naming ``name``."""
    if isinstance(value, np.ndarray):
        value = value.tolist() if value.ndim == 1 else None
    if not (isinstance(value, (tuple, list)) and len(value) == n and all(is_number(v) for v in value)
            and all(math.isfinite(v) for v in value)):
        raise ValueError(f"{name} must be {n} finite numbers ({what}), got {value!r}")
    return tuple(float(v) for v in value)


def _range(name: str, value: Any, lo: float, hi: float) -> tuple[float, float]:
    """A (min, max) pair with lo <= min <= max <= hi, as floats."""
    pair = _numbers(name, value, 2, "min, max in metres")
    if not lo <= pair[0] <= pair[1] <= hi:
        raise ValueError(f"{name} must be (min, max) with {lo:g} <= min <= max <= {hi:g} m, got {value!r}")
    return pair


@dataclass(frozen=True)
class VolumeSpec:
    """Parameters of a generated volume (every field is checked; tuples may be given as lists or arrays).

    Attributes:
        size: (x, y, z) extents of the volume, metres; x and y in [2, 30], z in [1, 5].
        obstacle_density: summed obstacle volume as a fraction of the volume, in [0, :data:`MAX_DENSITY`].
        ceiling: close the volume with a ceiling at z = size z (the top still bounds the grid without one).
        pole_radius: (min, max) radius of the vertical poles (tree trunks) that span floor to top, metres, within
            [0.01, 1].
        box_side: (min, max) side of a box, each of its three extents, metres, within [0.02, size z].
        beam_length: (min, max) length of a horizontal beam, metres, within [0.1, 30] (a beam may reach through
            the boundary).
        beam_thickness: (min, max) side of a beam's square cross-section, metres, within [0.01, size z / 2].
        wall_length: (min, max) length of a floor-to-top wall with one opening, metres, within [0.5, 30].
        wall_thickness: metres, in [0.02, 0.5].
        opening_size: (min, max) width and height of a wall's opening (a door or a window), metres, from 0.1; the
            largest must be shorter than the shortest wall and lower than the top.
        shape_probs: probabilities of (pole, box, beam, wall), non-negative and summing to 1.
        size_levels: evenly spaced values per size range, in [1, 10]; they bound the number of distinct bodies the
            pool keeps (``worlds/pool.py``).
        resolution: occupancy-grid cell size, metres, in [0.05, 0.5]; the volume takes at most
            :data:`MAX_CELLS` cells.
        spawn_clearance: free space around start and goal beyond the robot's radius, metres, in [0, 2].
        min_goal_distance: least straight-line start-goal distance as a fraction of the larger horizontal side,
            in (0, 1).
        max_attempts: layouts tried before giving up, in [1, 1000].
    """

    size: tuple[float, float, float] = (10.0, 10.0, 4.0)
    obstacle_density: float = 0.05
    ceiling: bool = True
    pole_radius: tuple[float, float] = (0.05, 0.25)
    box_side: tuple[float, float] = (0.3, 1.0)
    beam_length: tuple[float, float] = (1.5, 4.0)
    beam_thickness: tuple[float, float] = (0.08, 0.25)
    wall_length: tuple[float, float] = (2.0, 5.0)
    wall_thickness: float = 0.15
    opening_size: tuple[float, float] = (0.8, 1.6)
    shape_probs: tuple[float, float, float, float] = (0.4, 0.25, 0.2, 0.15)
    size_levels: int = 3
    resolution: float = 0.2
    spawn_clearance: float = 0.3
    min_goal_distance: float = 0.4
    max_attempts: int = 30

    def __post_init__(self) -> None:
        size = _numbers("size", self.size, 3, "x, y, z extents in metres")
        for axis, v, (lo, hi) in zip("xyz", size, SIZE_RANGE):
            if not lo <= v <= hi:
                raise ValueError(f"size {axis} must be in [{lo:g}, {hi:g}] m, got {v!r}")
        set_ = object.__setattr__
        set_(self, "size", size)
        set_(self, "obstacle_density", _number("obstacle_density", self.obstacle_density, 0.0, MAX_DENSITY))
        if not isinstance(self.ceiling, (bool, np.bool_)):
            raise ValueError(f"ceiling must be True or False, got {self.ceiling!r}")
        set_(self, "ceiling", bool(self.ceiling))
        longest = max(r[1] for r in SIZE_RANGE[:2])
        set_(self, "pole_radius", _range("pole_radius", self.pole_radius, 0.01, 1.0))
        set_(self, "box_side", _range("box_side", self.box_side, 0.02, size[2]))
        set_(self, "beam_length", _range("beam_length", self.beam_length, 0.1, longest))
        set_(self, "beam_thickness", _range("beam_thickness", self.beam_thickness, 0.01, 0.5 * size[2]))
        set_(self, "wall_length", _range("wall_length", self.wall_length, 0.5, longest))
        set_(self, "wall_thickness", _number("wall_thickness", self.wall_thickness, 0.02, 0.5))
        opening = _range("opening_size", self.opening_size, 0.1, longest)
        if not opening[1] < min(self.wall_length[0], size[2]):
            raise ValueError(f"opening_size max must be below the shortest wall_length ({self.wall_length[0]:g} m) "
                             f"and the height ({size[2]:g} m), got {opening[1]:g}")
        set_(self, "opening_size", opening)
        probs = _numbers("shape_probs", self.shape_probs, 4, "probabilities of pole, box, beam, wall")
        if min(probs) < 0.0 or abs(sum(probs) - 1.0) > 1e-9:
            raise ValueError(f"shape_probs must be 4 non-negative numbers summing to 1, got {self.shape_probs!r}")
        set_(self, "shape_probs", probs)
        check_integer("size_levels", self.size_levels, 1, 10)
        set_(self, "resolution", _number("resolution", self.resolution, 0.05, 0.5))
        cells = math.prod(max(1, round(v / self.resolution)) for v in size)
        if cells > MAX_CELLS:
            raise ValueError(f"resolution {self.resolution:g} m gives {cells} grid cells for size {size}; at most "
                             f"{MAX_CELLS} are allowed: coarsen the resolution or shrink the volume")
        set_(self, "spawn_clearance", _number("spawn_clearance", self.spawn_clearance, 0.0, 2.0))
        if not (is_number(self.min_goal_distance) and 0.0 < self.min_goal_distance < 1.0):
            raise ValueError(f"min_goal_distance must be a number in (0, 1) (fraction of the larger horizontal "
                             f"side), got {self.min_goal_distance!r}")
        check_integer("max_attempts", self.max_attempts, 1, 1000)

    @property
    def volume(self) -> float:
        """m^3 of the volume."""
        return math.prod(self.size)

    @cached_property
    def cell_centres(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cell-centre coordinates along x, y and z, metres (each axis split into whole cells of about
        ``resolution``)."""
        lows = (-0.5 * self.size[0], -0.5 * self.size[1], 0.0)
        out = []
        for low, extent in zip(lows, self.size):
            n = max(1, round(extent / self.resolution))
            out.append(low + (np.arange(n) + 0.5) * extent / n)
        return tuple(out)

    @cached_property
    def cell_size(self) -> np.ndarray:
        """(3,) cell edge along x, y and z, metres."""
        return np.array([extent / len(c) for extent, c in zip(self.size, self.cell_centres)])

    @cached_property
    def size_values(self) -> dict[str, np.ndarray]:
        """The ``size_levels`` evenly spaced values (1 mm grid) of each size range, by the range's name."""
        ranges = {"pole_radius": self.pole_radius, "box_side": self.box_side, "beam_length": self.beam_length,
                  "beam_thickness": self.beam_thickness, "wall_length": self.wall_length,
                  "opening_size": self.opening_size}
        return {name: np.round(np.linspace(lo, hi, self.size_levels), 3) for name, (lo, hi) in ranges.items()}
