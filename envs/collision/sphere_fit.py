"""A few spheres whose union encloses a collision mesh, for fast numpy clearance queries.

The *depth* of a point inside the mesh is its distance to the nearest surface point: a ball of that radius touches
the surface without crossing it, and grown by a bulge budget ``b`` it reaches at most ``b`` beyond the surface.
:func:`fit_spheres` picks, by greedy set cover over surface samples, at most ``n`` such balls that together hold
every sample, binary-searches the smallest ``b`` for which ``n`` balls suffice, then sets each radius so that the
union encloses the whole surface, not just the samples.

Depth is measured to the nearest surface sample and capped by the distance to the convex hull's boundary, so
nothing here needs the mesh to be closed or convex: a hole cannot let a ball reach more than ``b`` beyond the
hull. Candidate centres are approximate medial-axis points (the shrinking-ball construction: the largest ball
that touches a sample from the inside and holds no other sample), the centres of the biggest balls that fit,
plus a regular grid; only those inside the hull and on the inner side of the surface sample nearest them are
kept, so a notch that the hull fills gets no centres of its own.

Enclosure is exact, not sampled: a ball is convex, so it holds a triangle when it holds the triangle's three
corners. The mesh's triangles are split along their longest edges until each piece lies inside one ball, or is
small enough that growing the nearest-fitting ball to hold it costs little, and each ball's radius is the farthest
corner of the pieces it holds. :func:`enclosure_gap` checks a result on surface samples of its own.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError, cKDTree

_MEDIAL = 0.4  # medial-axis candidates, as a share of the surface samples
_GRID = 0.2  # grid candidates inside the hull, about, as a share of the surface samples
_SEARCH_STEPS = 12  # binary-search halvings of the bulge budget
_SHRINK_STEPS = 12  # shrinking-ball iterations
_PIECE = 0.005  # enclosure pieces stop splitting at this share of the mesh's bounding-box diagonal
_BLOCK = 4096  # points per block in the distance passes (bounds their memory)


def fit_spheres(mesh: trimesh.Trimesh, n: int, samples: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """At most ``n`` spheres whose union encloses the surface of ``mesh`` and bulges out of it as little as it can.

    Deterministic: the surface sampling is seeded here.

    Args:
        mesh: the triangle mesh, in metres; need not be watertight or convex.
        n: the most spheres to use, >= 1.
        samples: surface points the spheres are chosen to hold (the mesh's vertices are added); more give a
            slightly tighter fit, slower.

    Returns:
        ``(centres, radii)``: ``(m, 3)`` centres in the mesh's frame and ``(m,)`` radii, metres, ``m <= n``. The
        union holds every point of every triangle of ``mesh``.

    Raises:
        ValueError: ``n`` < 1.
    """
    centres, radii, _ = _fit(mesh, n, samples)
    return centres, radii


def enclosure_gap(mesh: trimesh.Trimesh, centres: np.ndarray, radii: np.ndarray, samples: int = 20000) -> float:
    """How far the surface of ``mesh`` sticks out of the union of spheres, at worst.

    The surface is probed at ``samples`` seeded points, independent of :func:`fit_spheres`'s, and at the mesh's
    vertices.

    Args:
        mesh: the triangle mesh, in metres.
        centres: ``(m, 3)`` sphere centres in the mesh's frame, metres.
        radii: ``(m,)`` sphere radii, metres.
        samples: surface points to probe.

    Returns:
        The largest distance from a probed point to the union, metres; 0 when every probed point is inside.
    """
    points, _ = _surface_samples(mesh, samples, seed=1)
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    gap = 0.0
    for start in range(0, len(points), _BLOCK):
        outside = _dist(points[start:start + _BLOCK], centres) - radii[None, :]
        gap = max(gap, float(outside.min(axis=1).max()))
    return gap


def _fit(mesh: trimesh.Trimesh, n: int, samples: int) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`fit_spheres`, and the bulge budget (metres) its set cover settled on."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    points, inward = _surface_samples(mesh, samples, seed=0)
    candidates, hull_depth = _candidates(points, inward)

    # Float32 about the samples' middle: ample for choosing centres; the final radii are computed in float64.
    origin = points.mean(axis=0)
    dist = _dist((points - origin).astype(np.float32), (candidates - origin).astype(np.float32))  # sample x candidate
    depth = np.minimum(dist.min(axis=0), hull_depth)
    slack = dist - depth[None, :]  # how far beyond its depth a candidate's ball must reach to hold a sample

    worst = slack.max(axis=0)
    chosen = np.array([int(np.argmin(worst))])
    lo, hi = 0.0, float(worst[chosen[0]])  # with budget hi one ball holds every sample
    for _ in range(_SEARCH_STEPS):
        mid = 0.5 * (lo + hi)
        picked = _greedy_cover(slack <= mid, n)
        if picked is None:
            lo = mid
        else:
            hi, chosen = mid, picked

    centres = candidates[chosen]
    piece = _PIECE * float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    radii = _enclosing_radii(np.asarray(mesh.triangles, dtype=float), centres, depth[chosen] + hi, piece)
    used = radii > 0.0
    return centres[used], radii[used], hi


def _surface_samples(mesh: trimesh.Trimesh, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` seeded surface samples followed by the mesh's distinct vertices (a seeded ``count`` of them when
    there are more), and the samples' ``(count, 3)`` inward unit normals: their faces' normals, turned over when
    the winding points them inwards on the whole."""
    sampled, face = trimesh.sample.sample_surface(mesh, count, seed=seed)
    normals = np.asarray(mesh.face_normals, dtype=float)
    centroid = np.asarray(mesh.vertices, dtype=float).mean(axis=0)
    outward = ((np.asarray(mesh.triangles_center) - centroid) * normals).sum(axis=1) @ np.asarray(mesh.area_faces)
    inward = normals[face] * (-1.0 if outward >= 0.0 else 1.0)
    vertices = np.unique(np.asarray(mesh.vertices, dtype=float), axis=0)
    if len(vertices) > count:
        vertices = vertices[np.sort(np.random.default_rng(seed).choice(len(vertices), count, replace=False))]
    return np.vstack([np.asarray(sampled, dtype=float), vertices]), inward


def _candidates(points: np.ndarray, inward: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate centres and their distances to the boundary of the convex hull of ``points``.

    Kept: those strictly inside the hull and on the inner side of the surface sample nearest them (which keeps
    them out of a notch the hull fills). A flat mesh has no inside: its samples are the candidates, at depth 0.
    """
    count = len(inward)
    try:
        hull = ConvexHull(points)
    except QhullError:  # flat: every point on one plane
        return points[:count], np.zeros(count)
    medial = _medial_centres(points, inward, int(_MEDIAL * count))
    candidates = np.vstack([medial, _grid(points, hull.volume, int(_GRID * count))])
    hull_depth = -(candidates @ hull.equations[:, :3].T + hull.equations[:, 3]).max(axis=1)
    _, nearest = cKDTree(points[:count]).query(candidates)
    behind = ((candidates - points[nearest]) * inward[nearest]).sum(axis=1) > 0.0
    keep = (hull_depth > 0.0) & behind
    if not keep.any():
        return points[:count], np.zeros(count)
    return candidates[keep], hull_depth[keep]


def _medial_centres(points: np.ndarray, inward: np.ndarray, count: int) -> np.ndarray:
    """Centres of the shrinking balls of the first ``count`` samples: for sample p with inward normal m, the ball
    about p + r m that passes through p, shrunk until no sample lies inside it (each step to the ball through p
    and the sample nearest the old centre)."""
    p, m = points[:count], inward[:count]
    tree = cKDTree(points)
    r = np.full(len(p), float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))))
    for _ in range(_SHRINK_STEPS):
        d, j = tree.query(p + r[:, None] * m)
        q = points[j] - p
        along = 2.0 * (q * m).sum(axis=1)
        shrink = (d < r * (1.0 - 1e-6)) & (along > 0.0)
        if not shrink.any():
            break
        r[shrink] = (q[shrink] * q[shrink]).sum(axis=1) / along[shrink]
    return p + r[:, None] * m


def _grid(points: np.ndarray, volume: float, count: int) -> np.ndarray:
    """A regular grid over the bounding box of ``points`` with about ``count`` points inside their convex hull
    (of ``volume``)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    step = max((volume / max(count, 1)) ** (1.0 / 3.0), float(np.linalg.norm(hi - lo)) / 64.0)
    axes = [np.arange(a + 0.5 * step, b, step) if b - a > step else np.array([0.5 * (a + b)]) for a, b in zip(lo, hi)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _greedy_cover(covers: np.ndarray, n: int) -> np.ndarray | None:
    """At most ``n`` columns of the boolean ``covers`` (sample x candidate) that together cover every row, each the
    column covering the most rows not yet covered; ``None`` when ``n`` columns do not suffice."""
    counts = np.count_nonzero(covers, axis=0)
    uncovered = np.ones(covers.shape[0], dtype=bool)
    chosen = []
    while uncovered.any():
        best = int(np.argmax(counts))
        if len(chosen) == n or counts[best] == 0:
            return None
        chosen.append(best)
        newly = covers[:, best] & uncovered
        uncovered &= ~newly
        counts = counts - np.count_nonzero(covers[newly], axis=0)
    return np.array(chosen)


def _enclosing_radii(triangles: np.ndarray, centres: np.ndarray, radii: np.ndarray, piece: float) -> np.ndarray:
    """Radii about ``centres`` whose balls together hold every one of ``triangles`` (``(t, 3, 3)`` corners).

    A triangle goes to the ball that holds it with the most room to spare under ``radii``; one that no ball holds
    is halved across its longest edge, down to pieces whose longest edge is ``piece``, which go to the ball
    that needs the least growth to hold them. Each ball's radius is then the farthest corner of what it got (0
    for a ball that got nothing).
    """
    out = np.zeros(len(centres))
    while len(triangles):
        reach = np.concatenate([  # farthest corner of each triangle from each centre
            _dist(block.reshape(-1, 3), centres).reshape(len(block), 3, len(centres)).max(axis=1)
            for block in np.array_split(triangles, max(1, len(triangles) // _BLOCK))
        ])
        owner = np.argmin(reach - radii[None, :], axis=1)
        need = reach[np.arange(len(triangles)), owner]
        lengths = np.linalg.norm(triangles - np.roll(triangles, -1, axis=1), axis=2)  # edge k: corners k, k + 1
        done = (need <= radii[owner]) | (lengths.max(axis=1) <= piece)
        np.maximum.at(out, owner[done], need[done])
        triangles, lengths = triangles[~done], lengths[~done]
        # Turn each triangle so that its longest edge joins corners 0 and 1, then halve that edge.
        order = (np.argmax(lengths, axis=1)[:, None] + np.arange(3)[None, :]) % 3
        t = np.take_along_axis(triangles, order[:, :, None], axis=1)
        mid = 0.5 * (t[:, 0] + t[:, 1])
        halves = np.stack([t[:, 0], mid, t[:, 2]], axis=1), np.stack([mid, t[:, 1], t[:, 2]], axis=1)
        triangles = np.concatenate(halves)
    return out


def _dist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(len(a), len(b))`` Euclidean distances between two point sets, in their dtype."""
    sq = (a * a).sum(axis=1)[:, None] - 2.0 * (a @ b.T) + (b * b).sum(axis=1)[None, :]
    return np.sqrt(np.maximum(sq, 0.0))
