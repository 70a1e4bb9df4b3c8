"""The compiled grid search behind ClutterFly's path field against scipy's Dijkstra on the explicit graph of the same
certified moves, built here edge by edge."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from clutter_gym.worlds.grid_search import FROM_SOURCE, UNREACHED, search_grid
from clutter_gym.worlds.volume.grid import scene_clearance
from clutter_gym.worlds.volume.path import VolumePathDistance, _moves
from clutter_gym.worlds.volume.sample import sample_volume_scene
from clutter_gym.worlds.volume.spec import VolumeSpec

R = 0.07  # metres: the default drone's bounding radius, about


def explicit_search(clear: np.ndarray, radius: float, moves: np.ndarray, lengths: np.ndarray, sources: np.ndarray,
                    source_lengths: np.ndarray) -> np.ndarray:
    """scipy's Dijkstra from an extra node joined to ``sources``, over every certified move as a listed edge."""
    shape, n = clear.shape, clear.size
    cells = np.indices(shape).reshape(3, -1).T
    rows, cols, data = [sources * 0 + n], [sources], [source_lengths]
    for move, length in zip(moves, lengths):
        target = cells + move
        inside = np.all((target >= 0) & (target < shape), axis=1)
        a, b = cells[inside], target[inside]
        ok = (clear[tuple(a.T)] > radius + 0.5 * length) & (clear[tuple(b.T)] > radius + 0.5 * length)
        rows.append(np.ravel_multi_index(tuple(a[ok].T), shape))
        cols.append(np.ravel_multi_index(tuple(b[ok].T), shape))
        data.append(np.full(int(ok.sum()), length))
    graph = coo_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(n + 1, n + 1))
    return dijkstra(graph.tocsr(), indices=n)[:n]


@pytest.mark.parametrize("density, seed", [(0.0, 0), (0.05, 1), (0.15, 2), (0.25, 3)])
def test_the_grid_search_finds_the_distances_of_the_explicit_graph(density, seed):
    spec = VolumeSpec(size=(6.0, 5.0, 3.0), obstacle_density=density)
    scene = sample_volume_scene(np.random.default_rng(seed), spec, R)
    field = VolumePathDistance(scene, spec, R)
    clear = scene_clearance(scene, spec, R + 2.0 * float(spec.cell_size.max()))
    moves, lengths = _moves(tuple(spec.cell_size.tolist()))
    sources, source_lengths = field._goal_links()
    distance, before = search_grid(clear, R + 0.5 * lengths, moves, lengths, sources, source_lengths)
    expected = explicit_search(clear, R, moves, lengths, sources, source_lengths)

    reached = np.isfinite(expected)
    np.testing.assert_array_equal(np.isfinite(distance), reached)
    np.testing.assert_allclose(distance[reached], expected[reached], rtol=1e-12, atol=0.0)
    np.testing.assert_array_equal(before[~reached], UNREACHED)
    # every reached cell's predecessor is a certified move (or the source link) that gives its distance exactly
    cells = np.indices(clear.shape).reshape(3, -1).T
    direct = before == FROM_SOURCE
    link = dict(zip(sources.tolist(), source_lengths.tolist()))
    assert set(np.flatnonzero(direct)) <= set(link) and direct.any()
    assert all(distance[c] == link[c] for c in np.flatnonzero(direct))
    assert all(distance[c] <= d for c, d in link.items())
    inner = np.flatnonzero(before >= 0)
    step = cells[inner] - cells[before[inner]]
    kind = np.array([np.flatnonzero((moves == s).all(axis=1))[0] for s in step])
    length = lengths[kind]
    limit = R + 0.5 * length
    assert (clear.ravel()[inner] > limit).all() and (clear.ravel()[before[inner]] > limit).all()
    np.testing.assert_array_equal(distance[inner], distance[before[inner]] + length)
    assert reached.sum() > 1000  # the search went through a good part of the volume


def test_a_cell_walled_off_from_the_source_is_unreached():
    # clearance 0.2 m per cell from the plane x = 3: within a cell of it no move is certified for a 0.1 m sphere (a
    # move of length L needs 0.1 + L / 2 at both ends), so the planes x = 2 to 4 split the grid in two
    clear = np.broadcast_to(0.2 * np.abs(np.arange(7) - 3.0)[:, None, None], (7, 7, 7)).copy()
    moves, lengths = _moves((0.2, 0.2, 0.2))
    distance, before = search_grid(clear, 0.1 + 0.5 * lengths, moves, lengths, np.array([0]), np.array([0.05]))
    half = distance.reshape(clear.shape)
    assert np.isfinite(half[:2]).all() and np.isinf(half[2:]).all()
    assert (before.reshape(clear.shape)[2:] == UNREACHED).all()
    # along the wall-side face x = 0 the grid distance to (0, 0, k) runs straight along z: k cell edges plus the link
    np.testing.assert_allclose(half[0, 0, :], 0.05 + 0.2 * np.arange(7), rtol=1e-14)
