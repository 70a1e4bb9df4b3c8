"""The clearance grid of a volume: exact signed distance from every cell centre to the nearest obstacle or face.

Why a chain of free cells is a collision-free path for a sphere of radius r (the drone's bounding sphere): the
signed distance d(p) to a union of solids is 1-Lipschitz (|d(p) - d(q)| <= |p - q|). Two cells that share a face
(6-connectivity) have centres at most h apart (h = the largest cell edge, :func:`free_margin`), and every point of
the segment between them lies within h / 2 of one of the two centres. So when both centres have d > r + h / 2,
every point of the segment has d > r: the sphere moved along it touches nothing. A 6-connected chain of such *free*
cells is therefore a collision-free path, and start and goal in one 6-connected free component (``scipy.ndimage.
label``'s default structure in 3D) are joined by one. The same argument with the move's own length L certifies any
straight move between two centres whose distances both exceed r + L / 2; the path distance
(``worlds/volume/path.py``) uses it for the face and body diagonals of the 26-neighbourhood.

The distances are exact (closed forms of yawed boxes and upright cylinders) and capped: an obstacle only matters
within ``cap`` of its bounding box, so each is evaluated on the window of cells around it and merged by minimum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.volume.scene import VolumeScene
from clutter_gym.worlds.volume.spec import VolumeSpec


def free_margin(spec: VolumeSpec) -> float:
    """Half the largest cell edge, metres: a cell is free when its clearance exceeds the robot radius plus this."""
    return 0.5 * float(spec.cell_size.max())


def signed_distance(o: Obstacle, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Signed distance (metres) from points (x, y, z) to ``o``'s surface, negative inside; the arguments
    broadcast against each other (world frame, metres)."""
    dx, dy = x - o.position[0], y - o.position[1]
    qz = np.abs(z - (o.z + 0.5 * o.size[2])) - 0.5 * o.size[2]
    if o.shape == "cylinder":
        radial = np.hypot(dx, dy) - o.radius
        return np.hypot(np.maximum(radial, 0.0), np.maximum(qz, 0.0)) + np.minimum(np.maximum(radial, qz), 0.0)
    c, s = math.cos(o.yaw), math.sin(o.yaw)
    qx = np.abs(c * dx + s * dy) - 0.5 * o.size[0]
    qy = np.abs(-s * dx + c * dy) - 0.5 * o.size[1]
    outside = np.sqrt(np.maximum(qx, 0.0) ** 2 + np.maximum(qy, 0.0) ** 2 + np.maximum(qz, 0.0) ** 2)
    return outside + np.minimum(np.maximum(np.maximum(qx, qy), qz), 0.0)


def bounding_box(o: Obstacle) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) corners (3,) of ``o``'s axis-aligned bounding box, world frame, metres."""
    if o.shape == "cylinder":
        hx = hy = o.radius
    else:
        c, s = abs(math.cos(o.yaw)), abs(math.sin(o.yaw))
        hx = 0.5 * (c * o.size[0] + s * o.size[1])
        hy = 0.5 * (s * o.size[0] + c * o.size[1])
    centre = np.array(o.centre)
    half = np.array([hx, hy, 0.5 * o.size[2]])
    return centre - half, centre + half


@dataclass(frozen=True)
class VolumeGrid:
    """A layout's clearance on the cell centres of ``spec`` (``values`` (nx, ny, nz), metres, capped at ``cap``)."""

    spec: VolumeSpec
    cap: float
    values: np.ndarray


def boundary_field(spec: VolumeSpec) -> np.ndarray:
    """(nx, ny, nz) distance from every cell centre to the nearest face of the volume, metres."""
    cx, cy, cz = spec.cell_centres
    sx, sy, sz = spec.size
    dx = (0.5 * sx - np.abs(cx))[:, None, None]
    dy = (0.5 * sy - np.abs(cy))[None, :, None]
    dz = np.minimum(cz, sz - cz)[None, None, :]
    return np.minimum(np.minimum(dx, dy), dz)


def clearance_field(obstacles: tuple[Obstacle, ...], spec: VolumeSpec, cap: float) -> np.ndarray:
    """(nx, ny, nz) distance from every cell centre to the nearest obstacle or face of the volume, capped at
    ``cap`` metres (exact below the cap)."""
    field = np.minimum(boundary_field(spec), cap)
    centres = spec.cell_centres
    h = spec.cell_size
    lows = np.array([c[0] for c in centres]) - 0.5 * h  # the grid's lower corner
    counts = np.array(field.shape)
    for o in obstacles:
        low, high = bounding_box(o)
        first = np.clip(np.floor((low - cap - lows) / h).astype(int), 0, counts)
        last = np.clip(np.ceil((high + cap - lows) / h).astype(int), 0, counts)
        if np.any(last <= first):
            continue  # wholly outside the volume
        (i0, j0, k0), (i1, j1, k1) = first, last
        d = signed_distance(o, centres[0][i0:i1, None, None], centres[1][None, j0:j1, None],
                            centres[2][None, None, k0:k1])
        window = field[i0:i1, j0:j1, k0:k1]
        np.minimum(window, d, out=window)
    return field


def scene_clearance(scene: VolumeScene, spec: VolumeSpec, cap: float) -> np.ndarray:
    """``clearance_field(scene.obstacles, spec, cap)``, cut from the grid the scene was drawn on when that one has
    the same spec and a cap no lower: the same numbers, as no obstacle comes nearer than ``cap`` to a cell that
    the window evaluation left out."""
    grid = scene.grid
    if grid is not None and grid.spec == spec and grid.cap >= cap:
        return np.minimum(grid.values, cap)
    return clearance_field(scene.obstacles, spec, cap)


def cell_index(point: tuple[float, ...] | np.ndarray, spec: VolumeSpec) -> tuple[int, int, int]:
    """(i, j, k) of the cell holding ``point`` (x, y, z), clipped to the grid."""
    out = []
    for p, c, h in zip(point[:3], spec.cell_centres, spec.cell_size):
        out.append(int(np.clip(math.floor((p - c[0]) / h + 0.5), 0, len(c) - 1)))
    return tuple(out)
