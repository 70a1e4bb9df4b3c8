"""Depth images of boxes and cylinders by casting one ray per pixel centre against each shape's exact surface.

A depth camera in a world of primitives needs no rasteriser: each pixel's depth is the nearest ray parameter at
which it meets a box (slab test) or a cylinder (a quadratic for the side, two planes for the caps). A shape is
tested only on the pixels of the rectangle its bounding box projects to, so a frame costs about the pixels times
the shapes stacked behind each, not the triangles of every visual in the world. Cylinders come out exact, not
tessellated.

Compiled with numba (cached on disk after the first call in a process).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Shape kinds in :func:`cast_depth`'s ``kinds``.
BOX, CYLINDER = 0, 1


@njit(cache=True)
def _box_hit(ex, ey, ez, dx, dy, dz, hx, hy, hz, near):
    """The smallest ray parameter >= near at which the ray e + t d meets the surface of the centred box with half
    extents h (inf if none)."""
    t_in, t_out = -np.inf, np.inf
    for e, d, h in ((ex, dx, hx), (ey, dy, hy), (ez, dz, hz)):
        if d == 0.0:
            if abs(e) > h:
                return np.inf
        else:
            t1, t2 = (-h - e) / d, (h - e) / d
            if t1 > t2:
                t1, t2 = t2, t1
            t_in, t_out = max(t_in, t1), min(t_out, t2)
            if t_in > t_out:
                return np.inf
    if t_in >= near:
        return t_in
    return t_out if t_out >= near else np.inf


@njit(cache=True)
def _cylinder_hit(ex, ey, ez, dx, dy, dz, radius, hz, near):
    """The smallest ray parameter >= near at which the ray e + t d meets the surface of the upright cylinder of
    ``radius`` and half height ``hz`` centred at the origin (inf if none)."""
    best = np.inf
    a = dx * dx + dy * dy
    if a > 0.0:
        b = ex * dx + ey * dy
        c = ex * ex + ey * ey - radius * radius
        disc = b * b - a * c
        if disc >= 0.0:
            root = math.sqrt(disc)
            for t in ((-b - root) / a, (-b + root) / a):
                if near <= t < best and abs(ez + t * dz) <= hz:
                    best = t
    if dz != 0.0:
        for cap in (-hz, hz):
            t = (cap - ez) / dz
            if near <= t < best:
                x, y = ex + t * dx, ey + t * dy
                if x * x + y * y <= radius * radius:
                    best = t
    return best


@njit(cache=True)
def cast_depth(eye, axes, fx, fy, cx, cy, near, far, kinds, centres, rotations, halves, depth, hit):
    """Fill ``depth`` and ``hit`` with what each pixel centre sees.

    Pixel (row j, column i) looks along ``forward + (i - cx) / fx * right + (j - cy) / fy * down``; the ray
    parameter along it is the depth along the optical axis. A pixel sees the nearest surface point with depth in
    [near, far): beyond a shape's part cut by the near plane it sees that shape's inside, as a rasteriser without
    back-face culling does.

    Args:
        eye: (3,) camera centre, world frame, metres.
        axes: (3, 3) rows forward, right and down (image rows grow downwards), world frame.
        fx, fy, cx, cy: pinhole intrinsics in pixels.
        near, far: metres.
        kinds: (n,) :data:`BOX` or :data:`CYLINDER`.
        centres: (n, 3) shape centres, world frame, metres.
        rotations: (n, 3, 3) shape axes as columns, world frame (a cylinder's axis is its third).
        halves: (n, 3) box half extents, or (radius, radius, half height) for a cylinder, metres.
        depth: (height, width) output, metres; pixels that see nothing are set to 0.
        hit: (height, width) output, the index of the shape each pixel sees, -1 for none.
    """
    height, width = depth.shape
    n = kinds.shape[0]
    rects, nearest = np.empty((n, 4), dtype=np.int64), np.empty(n)
    for k in range(n):
        nearest[k] = _image_rect(eye, axes, fx, fy, cx, cy, near, centres[k], rotations[k], halves[k], width, height,
                                 rects[k])
    depth[:] = np.inf
    hit[:] = -1
    for k in np.argsort(nearest):  # nearest first: a pixel that already sees something nearer skips the test
        if nearest[k] >= far:
            break
        rot, h = rotations[k], halves[k]
        # eye, forward, right and down in the shape's frame
        e, f, r, dn = (eye - centres[k]) @ rot, axes[0] @ rot, axes[1] @ rot, axes[2] @ rot
        i0, i1, j0, j1 = rects[k]
        for j in range(j0, j1 + 1):
            v = (j - cy) / fy
            for i in range(i0, i1 + 1):
                if depth[j, i] <= nearest[k]:
                    continue
                u = (i - cx) / fx
                dx, dy, dz = f[0] + u * r[0] + v * dn[0], f[1] + u * r[1] + v * dn[1], f[2] + u * r[2] + v * dn[2]
                if kinds[k] == BOX:
                    t = _box_hit(e[0], e[1], e[2], dx, dy, dz, h[0], h[1], h[2], near)
                else:
                    t = _cylinder_hit(e[0], e[1], e[2], dx, dy, dz, h[0], h[2], near)
                if t < depth[j, i] and t < far:
                    depth[j, i] = t
                    hit[j, i] = k
    for j in range(height):
        for i in range(width):
            if hit[j, i] < 0:
                depth[j, i] = 0.0


@njit(cache=True)
def _image_rect(eye, axes, fx, fy, cx, cy, near, centre, rot, h, width, height, rect):
    """Set ``rect`` to the pixel rectangle (i0, i1, j0, j1), inclusive, that holds the projection of the shape's
    bounding box cut at the near plane (its corners in front of the plane and the points where its edges cross
    it); return the smallest depth of that cut box (inf, and an empty rectangle, when it lies behind the plane)."""
    cam = np.empty((8, 3))  # rows: depth, right, down
    for corner in range(8):
        local = np.array([h[0] if corner & 1 else -h[0], h[1] if corner & 2 else -h[1], h[2] if corner & 4 else -h[2]])
        cam[corner] = axes @ (rot @ local + centre - eye)
    i0, i1, j0, j1, nearest = width, -1, height, -1, np.inf
    for a in range(8):
        for b in (a, a | 1, a | 2, a | 4):  # the corner itself, then its edges to greater corners
            za, zb = cam[a, 0], cam[b, 0]
            if b == a:
                if za < near:
                    continue
                x, y, z = cam[a, 1], cam[a, 2], za
            elif (za < near) != (zb < near):
                s = (near - za) / (zb - za)
                x, y, z = cam[a, 1] + s * (cam[b, 1] - cam[a, 1]), cam[a, 2] + s * (cam[b, 2] - cam[a, 2]), near
            else:
                continue
            nearest = min(nearest, z)
            u, v = cx + fx * x / z, cy + fy * y / z
            i0, i1 = min(i0, int(math.floor(u))), max(i1, int(math.ceil(u)))
            j0, j1 = min(j0, int(math.floor(v))), max(j1, int(math.ceil(v)))
    rect[0], rect[1], rect[2], rect[3] = max(i0, 0), min(i1, width - 1), max(j0, 0), min(j1, height - 1)
    return nearest
