"""Shortest-path distance to the goal through a volume, for a progress reward without local minima.

The field is the length of the shortest path on a graph of cell centres whose every edge is certified collision-free
for a sphere of the robot's radius r: a straight move of length L between two centres is an edge when both centres
have clearance above r + L / 2 (the Lipschitz argument of ``worlds/volume/grid.py``: every point of the move lies
within L / 2 of one end). The moves are the 26-neighbourhood and the (1, 2, 0) and (1, 1, 2) steps with their
permutations and signs (:data:`MOVES`); grid paths over them are at most 5% longer than the straight line in open
space (26 neighbours alone: 13%). In open space every move is an edge; next to obstacles only the short ones remain,
down to the 6 face moves, which is the connectivity the generator certified reachability with.

The goal joins the graph as one more node, linked to those of the eight cell centres around it whose segment to it
is certified the same way; the search (Dijkstra on the grid in place, ``worlds/grid_search.py``) runs once per
episode from it. A query point p takes the least of D(c) + |p - c| over the eight centres c around it whose segment
to p is certified. Each such value is the length of a collision-free path for the sphere, so the field is an upper
bound on the true shortest path length wherever a certified centre exists: at least wherever p's clearance exceeds r
plus a cell's diagonal and the centre nearest p is joined to the goal (that centre is then certified for p). When
one centre certifies the whole segment from p to the goal, the value is the straight distance itself. Elsewhere (the
sphere touching an obstacle, or a user's goal in a gap narrower than the grid certifies) the field continues as the
nearest reachable cell's value plus the straight distance to it, so a robot pushed against an obstacle still has a
finite, well-defined progress; it is not a bound there.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np

from clutter_gym.worlds.grid_search import search_grid
from clutter_gym.worlds.path_field import GridPathField
from clutter_gym.worlds.volume.grid import cell_index, scene_clearance
from clutter_gym.worlds.volume.scene import VolumeScene
from clutter_gym.worlds.volume.spec import VolumeSpec


@functools.cache
def _forward_moves() -> tuple[tuple[int, int, int], ...]:
    """One of each opposite pair of the moves (in cells): the 26-neighbourhood, (1, 2, 0) and (1, 1, 2) kinds."""
    moves = set()
    for kind in ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 2, 0), (1, 1, 2)):
        for perm in itertools.permutations(kind):
            for signs in itertools.product((-1, 1), repeat=3):
                move = tuple(a * b for a, b in zip(perm, signs))
                if move > (0, 0, 0):  # the first non-zero component positive: one per opposite pair
                    moves.add(move)
    return tuple(sorted(moves))


MOVES = _forward_moves()


@functools.cache
def _moves(h: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Every move (both directions; cells) and its length (metres, for cell edges ``h``)."""
    moves = np.array([*MOVES, *(tuple(-d for d in m) for m in MOVES)])
    return moves, np.linalg.norm(moves * np.array(h), axis=1)


class VolumePathDistance(GridPathField):
    """Path length from a point to the goal, metres, for a sphere of ``robot_radius`` (see the module docstring),
    and the path behind it (:meth:`path`, :meth:`waypoint`), whose first segment is certified only where the value
    is a bound.

    Args:
        scene: the episode's layout (obstacles and goal).
        spec: volume size and grid resolution.
        robot_radius: the robot's bounding radius, metres.
    """

    def __init__(self, scene: VolumeScene, spec: VolumeSpec, robot_radius: float) -> None:
        super().__init__(spec.cell_centres, spec.cell_size, scene.goal)
        self._spec = spec
        self._h_list = spec.cell_size.tolist()
        self._r = float(robot_radius)
        # above r + |p - c| for every centre c around a point p, so the cap never decides a certificate
        self._clear = scene_clearance(scene, spec, robot_radius + 2.0 * float(spec.cell_size.max()))
        self._clear_flat = self._clear.ravel()
        links, link_lengths = self._goal_links()
        moves, lengths = _moves(tuple(self._h_list))
        self._distance_flat, self._next = search_grid(self._clear, self._r + 0.5 * lengths, moves, lengths, links,
                                                      link_lengths)  # _next: each cell's next cell towards the goal
        self._distance = self._distance_flat.reshape(self._shape)

    def _around(self, point: tuple[float, ...]) -> list[tuple[int, float, tuple[float, float, float]]]:
        """(flat index, distance from ``point`` in metres, centre) of each of the (up to eight distinct) cell centres
        around ``point``; plain Python, as it runs once a step."""
        per_axis = []
        for p, c, h in zip(point, self._axes, self._h_list):
            i = min(max(math.floor((p - c[0]) / h), 0), max(len(c) - 2, 0))
            per_axis.append(sorted({i, min(i + 1, len(c) - 1)}))
        _, ny, nz = self._shape
        cx, cy, cz = self._axes
        out = []
        for i, j, k in itertools.product(*per_axis):
            centre = (cx[i], cy[j], cz[k])
            out.append(((i * ny + j) * nz + k, math.dist(point, centre), centre))
        return out

    def _goal_links(self) -> tuple[np.ndarray, np.ndarray]:
        """Cells the goal node links to and the link lengths: the certified centres around the goal, else the free
        cell nearest it (not certified: a goal in a gap the grid cannot resolve)."""
        around = [(flat, d) for flat, d, _ in self._around(self._goal) if self._clear_flat.item(flat) > self._r + d]
        if around:
            return np.array([f for f, _ in around]), np.array([d for _, d in around])
        free = np.flatnonzero(self._clear_flat > self._r + 0.5 * float(self._spec.cell_size.max()))
        if free.size == 0:
            return np.zeros(0, dtype=int), np.zeros(0)
        gaps = np.linalg.norm(self._cell_centres(free) - np.array(self._goal), axis=1)
        nearest = int(np.argmin(gaps))
        return free[nearest:nearest + 1], gaps[nearest:nearest + 1]

    def _best_corner(self, point: tuple[float, ...]) -> tuple[int, float] | None:
        """How ``point`` joins the graph: (-1, straight distance) when one centre around it certifies the whole
        segment to the goal, else (flat index, D(c) + |p - c|) of the certified centre c around it with the least
        value; None when no centre around it is certified."""
        best, best_cell = math.inf, -1
        for flat, d, centre in self._around(point):
            clear = self._clear_flat.item(flat)
            if clear > self._r + d:
                if clear > self._r + math.dist(centre, self._goal):  # every point of p-goal is within reach of c
                    return -1, math.dist(point, self._goal)
                value = self._distance_flat.item(flat) + d
                if value < best:
                    best, best_cell = value, flat
        return (best_cell, best) if best_cell >= 0 and math.isfinite(best) else None

    def _entry(self, point: tuple[float, ...]) -> int:
        """The certified centre around ``point`` that :meth:`_best_corner` picks (-1 where it certifies the straight
        segment to the goal), else the reachable cell nearest the cell holding ``point``."""
        best = self._best_corner(point)
        if best is not None:
            return best[0]
        return int(self._filled[1][np.ravel_multi_index(cell_index(point, self._spec), self._shape)])

    def __call__(self, x: float, y: float, z: float) -> float:
        """Path length (metres) from (x, y, z), world frame, to the goal."""
        point = (float(x), float(y), float(z))
        best = self._best_corner(point)
        if best is not None:
            return best[1]
        i, j, k = cell_index(point, self._spec)
        gap = math.dist(point, (self._axes[0][i], self._axes[1][j], self._axes[2][k]))
        return max(float(self.values[i, j, k]) + gap, math.dist(point, self._goal))
