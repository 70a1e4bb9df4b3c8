"""The checker's per-step arithmetic on a handful of shapes and obstacles, compiled with numba.

At a few shapes and tens of obstacles, numpy's per-call overhead costs more than the arithmetic: each of these
replaces a chain of small numpy calls on the step's hot path with one call (docs/benchmarks.md, "The exact LIDAR
caster and the envs' own vector env"). Each computes what the numpy it replaced did; a sum taken in another order
can differ in its last bits, which the bounds' slack (``nearest.BOUND_SLACK``) and the swept audit's threshold
absorb (the checker's reports over seeded runs of the three envs are unchanged).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def shape_travel(position, rotation, previous_position, previous_rotation, radii, moving):  # pragma: no cover
    """(len(moving),) how far any point of each moving shape travels on the screw motion between two poses
    (:class:`clutter_gym.collision.sweep.ScrewMotion`), metres, bounded from above: the rotation angle times its
    radius about its origin, plus its origin's displacement times angle / (2 sin(angle / 2)) (an arc over its chord:
    the twist's translation rate is at most that much longer than the displacement).

    Args:
        position, rotation: (n, 3) and (n, 3, 3) the shapes' poses now.
        previous_position, previous_rotation: the same at the last check.
        radii: (n,) each shape's radius about its origin.
        moving: indices of the shapes to answer for.
    """
    out = np.empty(len(moving))
    for row in range(len(moving)):
        i = moving[row]
        trace = 0.0
        for a in range(3):
            for b in range(3):
                trace += rotation[i, a, b] * previous_rotation[i, a, b]
        cos_angle = min(max((trace - 1.0) / 2.0, -1.0), 1.0)
        angle = math.acos(cos_angle)
        arc = angle / (2.0 * math.sin(0.5 * angle)) if angle > 1e-6 else 1.0
        dx = position[i, 0] - previous_position[i, 0]
        dy = position[i, 1] - previous_position[i, 1]
        dz = position[i, 2] - previous_position[i, 2]
        out[row] = arc * math.sqrt(dx * dx + dy * dy + dz * dz) + angle * radii[i]
    return out


@njit(cache=True, error_model="numpy")
def box_cylinder_distance(points, to_local, half, split, radius):  # pragma: no cover
    """(P, n) signed distance from each point to each of n obstacles: boxes in columns [0, split), upright
    cylinders after; positive outside, minus the depth to the nearest face inside.

    Args:
        points: (P, 3) world points.
        to_local: (4, 3 n) world -> obstacle frame on homogeneous points, columns x..., y..., z...
        half: (3, n) half extents (a cylinder's x is its radius, its y infinite).
        split: the number of boxes.
        radius: (n - split,) the cylinders' radii.
    """
    n = half.shape[1]
    out = np.empty((points.shape[0], n))
    for p in range(points.shape[0]):
        x, y, z = points[p, 0], points[p, 1], points[p, 2]
        for k in range(n):
            cx, cy, cz = k, n + k, 2 * n + k
            lx = x * to_local[0, cx] + y * to_local[1, cx] + z * to_local[2, cx] + to_local[3, cx]
            ly = x * to_local[0, cy] + y * to_local[1, cy] + z * to_local[2, cy] + to_local[3, cy]
            lz = x * to_local[0, cz] + y * to_local[1, cz] + z * to_local[2, cz] + to_local[3, cz]
            q0 = abs(lx) - half[0, k]
            q1 = abs(ly) - half[1, k]
            q2 = abs(lz) - half[2, k]
            if k >= split:
                q0 = math.hypot(lx, ly) - radius[k - split]
            o0, o1, o2 = max(q0, 0.0), max(q1, 0.0), max(q2, 0.0)
            out[p, k] = math.sqrt(o0 * o0 + o1 * o1 + o2 * o2) + min(max(q0, q1, q2), 0.0)
    return out
