"""Shortest paths from a source over the certified moves of a 2D or 3D clearance grid (Dijkstra, compiled with numba).

The graph is implicit: a move from one cell centre to another is an edge when the clearance at both centres, and at
the centres of the cells its segment passes through, exceeds the move's limit. The floor's field
(``worlds/floor/path.py``) gives every move the footprint radius as its limit and lists the cells a diagonal or
knight move crosses; the volume's (``worlds/volume/path.py``) gives a move of length L the limit ``radius + L / 2``
and needs no crossed cells (that module says why). Searching the grid in place, with no edge list, is what makes
this fast: building the explicit graph for ``scipy.sparse.csgraph`` cost more than searching it.

A move's weight is its length, times the mean of the two cells' ``cost`` when a costmap is given (a planner's
inflation layer). Distances are those of any Dijkstra on the same edges, bit for bit: a cell's distance is the least
of the sums ``distance[u] + weight`` over its settled neighbours, whatever order they settle in.

Ties: the heap pops equal distances in ascending (padded) cell index, a cell's moves are relaxed in the order given,
and only a strictly shorter path replaces a cell's predecessor, so the predecessors are a pure function of the inputs.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np

#: Predecessor of a cell the source links to directly, and of a cell the search never reaches.
FROM_SOURCE, UNREACHED = -2, -1
#: Cells of padding around the grid: the longest move spans two cells along an axis, so no move leaves the padding.
PAD = 2


def search_grid(clearance: np.ndarray, limits: np.ndarray, moves: np.ndarray, lengths: np.ndarray,
                sources: np.ndarray, source_lengths: np.ndarray, through: np.ndarray | None = None,
                cost: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Distances from a source node (joined to ``sources`` by links of ``source_lengths``) to every cell.

    Args:
        clearance: (nx, ny) or (nx, ny, nz) clearance of each cell centre, metres.
        limits: (m,) the clearance each move needs at its ends and crossed cells, metres.
        moves: (m, d) integer cell steps, each at most ``PAD`` cells along an axis.
        lengths: (m,) their lengths, metres.
        sources: flat indices of the cells the source links to.
        source_lengths: the links' lengths, metres.
        through: (m, k, d) cells each move's segment crosses, as steps from its start (repeat the start, a zero
            step, to fill a row); None when the ends alone decide.
        cost: clearance-shaped cost per metre of each cell (a move weighs its length times the mean of its ends');
            None for plain lengths.

    Returns:
        (n,) distances in metres (inf where unreachable) and (n,) each cell's predecessor: a flat cell index, or
        ``FROM_SOURCE``, or ``UNREACHED``.
    """
    layout = _padding(clearance.shape)
    padded = np.full(layout.shape, -np.inf)
    padded[layout.inside] = clearance
    moves = np.asarray(moves)
    crossed = np.zeros((len(moves), 0), dtype=np.int64) if through is None else np.asarray(through) @ layout.strides
    weights = np.ones(0)
    if cost is not None:
        weights = np.ones(padded.size)
        weights[layout.inner] = np.asarray(cost, dtype=float).ravel()
    distance, predecessor = _search(padded.ravel(), np.asarray(limits, dtype=float), moves @ layout.strides,
                                    crossed.astype(np.int64), np.asarray(lengths, dtype=float), weights,
                                    layout.inner[np.asarray(sources, dtype=np.int64)],
                                    np.asarray(source_lengths, dtype=float))
    before = predecessor[layout.inner]
    return distance[layout.inner], np.where(before >= 0, layout.cell[np.maximum(before, 0)], before)


@dataclass(frozen=True)
class _Padding:
    """A grid of some shape inside ``PAD`` cells of padding: the padded ``shape``, its flat ``strides``, the slices
    of the grid in it (``inside``), each grid cell's flat padded index (``inner``), and each padded cell's flat grid
    index (``cell``; ``UNREACHED`` in the padding)."""

    shape: tuple[int, ...]
    strides: np.ndarray
    inside: tuple[slice, ...]
    inner: np.ndarray
    cell: np.ndarray


@functools.cache
def _padding(shape: tuple[int, ...]) -> _Padding:
    padded = tuple(k + 2 * PAD for k in shape)
    inner = np.ravel_multi_index(tuple(np.indices(shape).reshape(len(shape), -1) + PAD), padded)
    cell = np.full(math.prod(padded), UNREACHED, dtype=np.int64)
    cell[inner] = np.arange(inner.size)
    strides = np.array([math.prod(padded[i + 1:]) for i in range(len(shape))])
    return _Padding(padded, strides, tuple(slice(PAD, PAD + k) for k in shape), inner, cell)


@numba.njit(cache=True)
def _search(clear, limits, offsets, crossed, lengths, cost, sources, source_lengths):  # pragma: no cover (compiled)
    """Dijkstra over the padded grid ``clear`` (flat clearance, -inf in the padding), with an indexed binary heap.

    ``cost`` is empty for plain lengths. ``where`` holds each cell's heap position, -1 before it enters the heap and
    -2 once settled. ``open_`` is the clearance with every settled cell's overwritten with -inf, so that no move is
    certified into it again without a second lookup. ``clear`` is overwritten so too when no move crosses cells, and
    copied first when some do (crossed cells are read from ``clear`` itself).
    """
    n = clear.size
    open_ = clear.copy() if crossed.shape[1] > 0 else clear
    distance = np.full(n, np.inf)
    predecessor = np.full(n, UNREACHED, dtype=np.int64)
    heap = np.empty(n, dtype=np.int64)
    where = np.full(n, -1, dtype=np.int64)
    weighted = cost.size > 0
    n_crossed = crossed.shape[1]
    size = 0
    for s in range(sources.size):
        v = sources[s]
        if source_lengths[s] < distance[v]:
            distance[v] = source_lengths[s]
            predecessor[v] = FROM_SOURCE
            size = _lowered(heap, where, distance, v, size)
    while size > 0:
        u = heap[0]
        where[u] = -2
        size -= 1
        if size > 0:
            heap[0] = heap[size]
            where[heap[0]] = 0
            _sift_down(heap, where, distance, size)
        base, clear_u = distance[u], open_[u]
        open_[u] = -np.inf
        for m in range(offsets.size):
            limit = limits[m]
            if clear_u <= limit:
                continue
            v = u + offsets[m]
            if open_[v] <= limit:
                continue
            d = base + (lengths[m] * (0.5 * (cost[u] + cost[v])) if weighted else lengths[m])
            if d >= distance[v]:
                continue
            blocked = False
            for c in range(n_crossed):
                if clear[u + crossed[m, c]] <= limit:
                    blocked = True
                    break
            if not blocked:
                distance[v] = d
                predecessor[v] = u
                size = _lowered(heap, where, distance, v, size)
    return distance, predecessor
@numba.njit(cache=True, inline="always")
def _lowered(heap, where, distance, cell, size):  # pragma: no cover (compiled)
    """Move ``cell``, whose distance just fell, up to its place in the heap (adding it if it is not in it); the
    heap's new size."""
    if where[cell] < 0:
        heap[size] = cell
        where[cell] = size
        size += 1
    _sift_up(heap, where, distance, where[cell])
    return size


@numba.njit(cache=True, inline="always")
def _before(a, b, distance):  # pragma: no cover (compiled)
    """Heap order: nearer first, then the lower index."""
    return distance[a] < distance[b] or (distance[a] == distance[b] and a < b)


@numba.njit(cache=True)
def _sift_up(heap, where, distance, position):  # pragma: no cover (compiled)
    node = heap[position]
    while position > 0:
        parent = (position - 1) >> 1
        if _before(heap[parent], node, distance):
            break
        heap[position] = heap[parent]
        where[heap[position]] = position
        position = parent
    heap[position] = node
    where[node] = position


@numba.njit(cache=True)
def _sift_down(heap, where, distance, size):  # pragma: no cover (compiled)
    node = heap[0]
    position = 0
    while True:
        child = 2 * position + 1
        if child >= size:
            break
        if child + 1 < size and _before(heap[child + 1], heap[child], distance):
            child += 1
        if _before(node, heap[child], distance):
            break
        heap[position] = heap[child]
        where[heap[position]] = position
        position = child
    heap[position] = node
    where[node] = position
