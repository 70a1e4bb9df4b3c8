"""The part of a path-distance field that the floor's (2D) and the volume's (3D) share.

Each world's field runs its own search from the goal over its own certified moves (``worlds/grid_search.py``) and
says how a query point joins the grid: ``worlds/floor/path.py`` and ``worlds/volume/path.py``. What is left is the
same for both, and lives here: the field's finite continuation over the cells the goal cannot be reached from, and
the path behind a value, followed cell by cell to the goal, with the point a given length along it.
"""

from __future__ import annotations

import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Iterator, Sequence

import numpy as np
from scipy import ndimage


class GridPathField(ABC):
    """Path length to the goal over a grid of cell centres, the path behind it, and points along that path.

    A subclass runs its search after calling this constructor and sets :attr:`_distance` and :attr:`_next` from it,
    and says at which cell a query point joins the path (:meth:`_entry`).

    Args:
        centres: cell-centre coordinates along each axis, metres.
        cell_size: the cells' edge, metres: one number for square cells, whose gaps to the nearest reachable cell
            are counted in cells and then scaled (the floor's), or one per axis (the volume's).
        goal: the goal point, metres.
    """

    #: (the grid's shape) the searched path length from each cell centre to the goal, metres; inf where the goal
    #: cannot be reached from it.
    _distance: np.ndarray
    #: (cells,) each cell's next cell towards the goal, as a flat index (negative where the path leaves the grid:
    #: ``grid_search.FROM_SOURCE``); None where the field was made without its paths.
    _next: np.ndarray | None = None
    #: The cell whose centre stands for the goal, left out of every path: the floor searches from the goal's cell.
    #: None where the search starts from the goal point itself (the volume's links it to the cells around it).
    _goal_cell: int | None = None

    def __init__(self, centres: Sequence[np.ndarray], cell_size: float | np.ndarray,
                 goal: Sequence[float]) -> None:
        self._centres = tuple(np.asarray(c) for c in centres)
        self._axes = tuple(c.tolist() for c in self._centres)  # plain floats, for the per-step lookups
        self._shape = tuple(len(c) for c in self._axes)
        self._strides = tuple(math.prod(self._shape[i + 1:]) for i in range(len(self._shape)))
        self._cell_size = cell_size
        self._goal = tuple(float(v) for v in goal)

    @abstractmethod
    def _entry(self, point: tuple[float, ...]) -> int:
        """The flat index of the cell where the path from ``point`` joins the grid (negative: none)."""

    @property
    def values(self) -> np.ndarray:
        """(the grid's shape) the field at the cell centres, metres (finite everywhere)."""
        return self._filled[0]

    @functools.cached_property
    def _filled(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_fill_unreachable`, on first use: a field read only where it is certified never needs it."""
        return self._fill_unreachable()

    def _fill_unreachable(self) -> tuple[np.ndarray, np.ndarray]:
        """The field with each unreachable cell given the nearest reachable cell's value plus the straight distance
        to it (the straight distance to the goal when nothing is reachable), and (cells,) each cell's nearest
        reachable cell, a flat index (itself where reachable; -1 when nothing is)."""
        reachable = np.isfinite(self._distance)
        if not reachable.any():
            centres = self._cell_centres(np.arange(reachable.size))
            straight = np.linalg.norm(centres - np.array(self._goal), axis=1).reshape(reachable.shape)
            return straight, np.full(reachable.size, -1)
        if np.ndim(self._cell_size) == 0:
            cells, nearest = ndimage.distance_transform_edt(~reachable, return_indices=True)
            gap = cells * self._cell_size
        else:
            gap, nearest = ndimage.distance_transform_edt(~reachable, sampling=self._cell_size, return_indices=True)
        return self._distance[tuple(nearest)] + gap, np.ravel_multi_index(tuple(nearest), reachable.shape).ravel()

    def _cell_centres(self, flat: np.ndarray) -> np.ndarray:
        """(k, d) centres of the cells with flat indices ``flat``, metres."""
        cells = np.unravel_index(flat, self._shape)
        return np.stack([c[i] for c, i in zip(self._centres, cells)], axis=1)

    def _centre(self, cell: int) -> tuple[float, ...]:
        """The centre of the cell with flat index ``cell``, metres (plain Python: it runs along every path)."""
        out = []
        for axis, stride in zip(self._axes, self._strides):
            i, cell = divmod(cell, stride)
            out.append(axis[i])
        return tuple(out)

    def path(self, *point: float) -> np.ndarray:
        """(k, d) the path behind the field's value at ``point`` (its d coordinates, metres): the point, the centres
        of the cells the path passes, the goal.

        Raises:
            RuntimeError: the field was made without its paths.
        """
        return np.array(list(self._chain(point)))

    def waypoint(self, *point: float, lookahead: float) -> tuple[float, ...]:
        """The point ``lookahead`` metres along :meth:`path` from ``point`` (the goal if nearer), metres; walks the
        path only as far as it needs.

        Raises:
            RuntimeError: the field was made without its paths.
        """
        points = self._chain(point)
        previous, travelled = next(points), 0.0
        for current in points:
            step = math.dist(previous, current)
            if travelled + step >= lookahead and step > 0.0:
                t = (lookahead - travelled) / step
                return tuple(a + t * (b - a) for a, b in zip(previous, current))
            travelled += step
            previous = current
        return self._goal

    def _chain(self, point: Sequence[float]) -> Iterator[tuple[float, ...]]:
        """``point``, then the centres of the cells of its path (see :meth:`path`), then the goal."""
        if self._next is None:
            raise RuntimeError(f"the planned path needs a {type(self).__name__} made with a plan_margin")
        if len(point) != len(self._shape):
            raise ValueError(f"a point on this grid has {len(self._shape)} coordinates, got {point!r}")
        start = tuple(float(v) for v in point)
        yield start
        cell = self._entry(start)
        while cell >= 0 and cell != self._goal_cell:
            yield self._centre(cell)
            cell = int(self._next[cell])
        yield self._goal
