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
from collections.abc import Iterator

import numpy as np
from scipy import ndimage

from clutter_gym.worlds.grid_search import FROM_SOURCE, search_grid
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


class VolumePathDistance:
    """Path length from a point to the goal, metres, for a sphere of ``robot_radius`` (see the module docstring).

    Args:
        scene: the episode's layout (obstacles and goal).
        spec: volume size and grid resolution.
        robot_radius: the robot's bounding radius, metres.
    """

    def __init__(self, scene: VolumeScene, spec: VolumeSpec, robot_radius: float) -> None:
        self._spec = spec
        self._centres = spec.cell_centres
        self._h = spec.cell_size
        self._axes = tuple(c.tolist() for c in self._centres)
        self._h_list = self._h.tolist()
        self._r = float(robot_radius)
        self._goal = tuple(float(v) for v in scene.goal)
        # above r + |p - c| for every centre c around a point p, so the cap never decides a certificate
        self._clear = scene_clearance(scene, spec, robot_radius + 2.0 * float(self._h.max()))
        self._clear_flat = self._clear.ravel()
        links, link_lengths = self._goal_links()
        moves, lengths = _moves(tuple(self._h_list))
        self._distance_flat, self._next = search_grid(self._clear, self._r + 0.5 * lengths, moves, lengths, links,
                                                      link_lengths)  # _next: each cell's next cell towards the goal
        self._distance = self._distance_flat.reshape(self._clear.shape)

    @property
    def values(self) -> np.ndarray:
        """(nx, ny, nz) the field at the cell centres, metres (finite everywhere)."""
        return self._filled[0]

    @functools.cached_property
    def _filled(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_fill_unreachable`, on first use: a robot that never leaves the certified cells never needs it."""
        return self._fill_unreachable()

    def _around(self, point: tuple[float, float, float]) -> list[tuple[int, float, tuple[float, float, float]]]:
        """(flat index, distance from ``point`` in metres, centre) of each of the (up to eight distinct) cell centres
        around ``point``; plain Python, as it runs once a step."""
        per_axis = []
        for p, c, h in zip(point, self._axes, self._h_list):
            i = min(max(math.floor((p - c[0]) / h), 0), max(len(c) - 2, 0))
            per_axis.append(sorted({i, min(i + 1, len(c) - 1)}))
        _, ny, nz = self._clear.shape
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
        free = np.flatnonzero(self._clear_flat > self._r + 0.5 * float(self._h.max()))
        if free.size == 0:
            return np.zeros(0, dtype=int), np.zeros(0)
        gaps = np.linalg.norm(self._cell_centres(free) - np.array(self._goal), axis=1)
        nearest = int(np.argmin(gaps))
        return free[nearest:nearest + 1], gaps[nearest:nearest + 1]

    def _cell_centres(self, flat: np.ndarray) -> np.ndarray:
        """(k, 3) centres of the cells with flat indices ``flat``, metres."""
        cells = np.unravel_index(flat, self._clear.shape)
        return np.stack([c[i] for c, i in zip(self._centres, cells)], axis=1)

    def _fill_unreachable(self) -> tuple[np.ndarray, np.ndarray]:
        """The field with unreachable cells given the nearest reachable cell's value plus the straight distance
        to it (the straight distance to the goal when nothing is reachable), and (n,) each cell's nearest reachable
        cell (itself where reachable; -1 when nothing is)."""
        reachable = np.isfinite(self._distance)
        if not reachable.any():
            centres = self._cell_centres(np.arange(reachable.size))
            straight = np.linalg.norm(centres - np.array(self._goal), axis=1).reshape(reachable.shape)
            return straight, np.full(reachable.size, -1)
        gap, nearest = ndimage.distance_transform_edt(~reachable, sampling=self._h, return_indices=True)
        return self._distance[tuple(nearest)] + gap, np.ravel_multi_index(tuple(nearest), reachable.shape).ravel()

    def _best_corner(self, point: tuple[float, float, float]) -> tuple[int, float] | None:
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

    def __call__(self, x: float, y: float, z: float) -> float:
        """Path length (metres) from (x, y, z), world frame, to the goal."""
        point = (float(x), float(y), float(z))
        best = self._best_corner(point)
        if best is not None:
            return best[1]
        i, j, k = cell_index(point, self._spec)
        gap = math.dist(point, (self._axes[0][i], self._axes[1][j], self._axes[2][k]))
        return max(float(self.values[i, j, k]) + gap, math.dist(point, self._goal))

    def path(self, x: float, y: float, z: float) -> np.ndarray:
        """(k, 3) the path behind the field's value at (x, y, z): the point, the cell centres, the goal (metres).

        Its first segment is certified only where the value is a bound (see the module docstring)."""
        return np.array(list(self._chain((float(x), float(y), float(z)))))

    def waypoint(self, x: float, y: float, z: float, lookahead: float) -> tuple[float, float, float]:
        """The point ``lookahead`` metres along :meth:`path` from (x, y, z) (the goal if nearer), metres; walks
        the path only as far as it needs."""
        points = self._chain((float(x), float(y), float(z)))
        previous, travelled = next(points), 0.0
        for point in points:
            step = math.dist(previous, point)
            if travelled + step >= lookahead and step > 0.0:
                t = (lookahead - travelled) / step
                return tuple(a + t * (b - a) for a, b in zip(previous, point))
            travelled += step
            previous = point
        return self._goal

    def _chain(self, point: tuple[float, float, float]) -> Iterator[tuple[float, float, float]]:
        """``point``, then the cell centres of its path (see :meth:`path`), then the goal."""
        yield point
        best = self._best_corner(point)
        if best is not None:
            cell = best[0]
        else:
            cell = int(self._filled[1][np.ravel_multi_index(cell_index(point, self._spec), self._clear.shape)])
        if cell >= 0:
            _, ny, nz = self._clear.shape
            cx, cy, cz = self._axes
            while cell != FROM_SOURCE:
                i, rest = divmod(cell, ny * nz)
                j, k = divmod(rest, nz)
                yield (cx[i], cy[j], cz[k])
                cell = int(self._next[cell])
        yield self._goal
