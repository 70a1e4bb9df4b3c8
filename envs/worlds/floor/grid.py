"""The clearance field of a floor layout: exact signed distance from every cell centre of the occupancy grid to the
nearest obstacle footprint or arena wall, capped, evaluated only in each obstacle's window.

The sampler draws start and goal on it (``worlds/floor/sample.py``) and the scene keeps it
(``Scene.clearance_grid``), so that the path distance (``worlds/floor/path.py``) need not compute it again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.floor.scene import Scene
from clutter_gym.worlds.floor.spec import ClutterSpec


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
