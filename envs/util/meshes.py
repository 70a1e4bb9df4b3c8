"""Triangle meshes built with numpy, for shapes pybullet represents better as meshes than as primitives."""

from __future__ import annotations

import math

import numpy as np


def prism_mesh(radius: float, height: float, sides: int) -> tuple[list[list[float]], list[int]]:
    """Triangle mesh of an upright ``sides``-gon prism centred at the origin, with the circle's area.

    The polygon's circumradius is ``r * sqrt(2 pi / (n sin(2 pi / n)))``, so that on average it neither grows
    nor shrinks the cylinder it stands for. The side and the top cap are meshed; the bottom cap is left out: on
    an obstacle standing on the floor nothing can touch it, and its fan triangles reach across the whole disc,
    so they sit inside the bounding box of every wheel near the obstacle (7% of the physics cost in clutter).
    Triangles wind counter-clockwise seen from outside.
    """
    n = sides
    big_r = radius * math.sqrt(2 * math.pi / (n * math.sin(2 * math.pi / n)))
    a = 2 * math.pi * np.arange(n) / n
    ring = np.stack([big_r * np.cos(a), big_r * np.sin(a)], axis=1)
    h = 0.5 * height
    vertices = np.vstack([np.c_[ring, np.full(n, -h)], np.c_[ring, np.full(n, h)], [[0.0, 0.0, h]]])
    i = np.arange(n)
    j = (i + 1) % n
    top = np.full(n, 2 * n)
    faces = np.concatenate([np.stack([i, j, n + j], 1), np.stack([i, n + j, n + i], 1),
                            np.stack([top, n + i, n + j], 1)])
    return vertices.tolist(), faces.ravel().tolist()
