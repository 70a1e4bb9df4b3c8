"""Shortest paths from a source over the certified moves of a 3D clearance grid (Dijkstra, compiled with numba).

The graph is implicit: a move of length L from one cell centre to another is an edge when both centres have
clearance above ``radius + L / 2`` (``worlds/volume_path.py`` says why that certifies it). Searching the grid in
place, with no edge list, is what makes this fast: building the explicit graph for ``scipy.sparse.csgraph`` cost
more than searching it.

Ties: the heap pops equal distances in ascending (padded) cell index, a cell's moves are relaxed in the order given,
and only a strictly shorter path replaces a cell's predecessor, so the result is a pure function of the inputs.
"""

from __future__ import annotations

import numba
import numpy as np

#: Predecessor of a cell the source links to directly, and of a cell the search never reaches.
FROM_SOURCE, UNREACHED = -2, -1
#: Cells of padding around the grid: the longest move spans two cells along an axis, so no move leaves the padding.
PAD = 2


def search_grid(clearance: np.ndarray, radius: float, moves: np.ndarray, lengths: np.ndarray,
                sources: np.ndarray, source_lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distances from a source node (joined to ``sources`` by links of ``source_lengths``) to every cell.

    Args:
        clearance: (nx, ny, nz) clearance of each cell centre, metres.
        radius: the robot's radius, metres.
        moves: (m, 3) integer cell steps, each at most ``PAD`` cells along an axis.
        lengths: (m,) their lengths, metres.
        sources: flat indices of the cells the source links to.
        source_lengths: the links' lengths, metres.

    Returns:
        (n,) distances in metres (inf where unreachable) and (n,) each cell's predecessor: a flat cell index, or
        ``FROM_SOURCE``, or ``UNREACHED``.
    """
    shape = clearance.shape
    padded = np.full(tuple(k + 2 * PAD for k in shape), -np.inf)
    padded[PAD:-PAD, PAD:-PAD, PAD:-PAD] = clearance
    strides = np.array([padded.shape[1] * padded.shape[2], padded.shape[2], 1])
    inner = np.ravel_multi_index(tuple(np.indices(shape).reshape(3, -1) + PAD), padded.shape)
    distance, predecessor = _search(padded.ravel(), radius + 0.5 * np.asarray(lengths, dtype=float),
                                    np.asarray(moves) @ strides, np.asarray(lengths, dtype=float),
                                    inner[np.asarray(sources, dtype=np.int64)],
                                    np.asarray(source_lengths, dtype=float))
    cell = np.full(padded.size, UNREACHED, dtype=np.int64)
    cell[inner] = np.arange(inner.size)
    before = predecessor[inner]
    return distance[inner], np.where(before >= 0, cell[np.maximum(before, 0)], before)


@numba.njit(cache=True)
def _search(free, limits, offsets, lengths, sources, source_lengths):  # pragma: no cover (compiled)
    """Dijkstra over the padded grid ``free`` (flat clearance, -inf in the padding), with an indexed binary heap.

    A settled cell's clearance is overwritten with -inf, so no move is certified into it again. ``where`` holds
    each cell's heap position, -1 before it enters the heap and -2 once settled.
    """
    n = free.size
    distance = np.full(n, np.inf)
    predecessor = np.full(n, UNREACHED, dtype=np.int64)
    heap = np.empty(n, dtype=np.int64)
    where = np.full(n, -1, dtype=np.int64)
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
        clear = free[u]
        free[u] = -np.inf
        base = distance[u]
        for m in range(offsets.size):
            if clear <= limits[m]:
                continue
            v = u + offsets[m]
            if free[v] <= limits[m]:
                continue
            d = base + lengths[m]
            if d < distance[v]:
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
