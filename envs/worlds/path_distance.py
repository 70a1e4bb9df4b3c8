"""Shortest-path distance to the goal around the clutter, for reward shaping that has no local minima.

The straight-line distance to the goal rewards driving into a U of obstacles; the path distance does not: it is
the length of the shortest 16-connected grid path through cells where the robot's footprint fits (clearance
above its radius), computed once per episode by Dijkstra from the goal cell. Cells the footprint does not fit
in (the robot touching an obstacle) take the value of the nearest reachable cell plus the distance to it, so
the field is finite everywhere and a robot pushed against an obstacle still has a well-defined progress.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from clutter_gym.worlds.clutter import ClutterSpec, clearance_field
from clutter_gym.worlds.scene import Scene

# Forward moves (di, dj) of the 16-neighbourhood (their mirror images are the same undirected edges), each with
# the cells its segment passes through, which must be free too. 16 neighbours bound the path-length error in
# open space to 2.7% (8 neighbours: 8.2%).
_MOVES = (
    ((1, 0), ()), ((0, 1), ()),
    ((1, 1), ((1, 0), (0, 1))), ((1, -1), ((1, 0), (0, -1))),
    ((2, 1), ((1, 0), (1, 1))), ((1, 2), ((0, 1), (1, 1))),
    ((2, -1), ((1, 0), (1, -1))), ((1, -2), ((0, -1), (1, -1))),
)


class PathDistance:
    """Path length from a point to the goal, metres (bilinear in the cell-centre values).

    Args:
        scene: the episode's layout (obstacles and goal).
        spec: arena size and grid resolution.
        robot_radius: footprint radius, metres.
    """

    def __init__(self, scene: Scene, spec: ClutterSpec, robot_radius: float) -> None:
        self._centres = spec.cell_centres
        self._res = float(self._centres[1] - self._centres[0])
        self._origin, self._top = float(self._centres[0]), float(len(self._centres) - 1)  # first centre, last index
        clearance = clearance_field(scene.obstacles, spec, cap=robot_radius + self._res)
        free = clearance > robot_radius
        goal_cell = self._nearest_cell(scene.goal)
        free[goal_cell] = True
        self.values = _fill_unreachable(_dijkstra_from(goal_cell, free, self._res), self._res)
        self._goal = scene.goal

    def _nearest_cell(self, point: tuple[float, float]) -> tuple[int, int]:
        n = len(self._centres)
        return tuple(int(np.clip(round((p - self._centres[0]) / self._res), 0, n - 1)) for p in point)

    def __call__(self, x: float, y: float) -> float:
        top = self._top
        fx = min(max((x - self._origin) / self._res, 0.0), top)
        fy = min(max((y - self._origin) / self._res, 0.0), top)
        i, j = min(int(fx), int(top) - 1), min(int(fy), int(top) - 1)
        tx, ty = fx - i, fy - j
        v = self.values
        grid = ((1 - tx) * (1 - ty) * v[i, j] + tx * (1 - ty) * v[i + 1, j]
                + (1 - tx) * ty * v[i, j + 1] + tx * ty * v[i + 1, j + 1])
        # The grid path can only be longer than the straight line; near the goal it is coarse, so clamp.
        return max(float(grid), math.hypot(x - self._goal[0], y - self._goal[1]))


def _dijkstra_from(source: tuple[int, int], free: np.ndarray, res: float) -> np.ndarray:
    """(n, n) shortest 16-connected path length through ``free`` cells from ``source``; inf where unreachable."""
    n = free.shape[0]
    padded = np.pad(free, 2, constant_values=False)

    def shifted(di: int, dj: int) -> np.ndarray:  # shifted(di, dj)[i, j] = free[i + di, j + dj], False outside
        return padded[2 + di:2 + di + n, 2 + dj:2 + dj + n]

    rows, cols, weights = [], [], []
    for (di, dj), through in _MOVES:
        ok = free & shifted(di, dj)
        for cell in through:
            ok &= shifted(*cell)
        source_ids = np.flatnonzero(ok)
        rows.append(source_ids)
        cols.append(source_ids + di * n + dj)
        weights.append(np.full(source_ids.size, res * math.hypot(di, dj)))
    graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(n * n, n * n))
    return dijkstra(graph.tocsr(), directed=False, indices=source[0] * n + source[1]).reshape(n, n)


def _fill_unreachable(distance: np.ndarray, res: float) -> np.ndarray:
    """Unreachable cells get the nearest reachable cell's value plus the straight distance to it."""
    reachable = np.isfinite(distance)
    gap, (ni, nj) = ndimage.distance_transform_edt(~reachable, return_indices=True)
    return distance[ni, nj] + gap * res
