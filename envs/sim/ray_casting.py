"""Depth images and LIDAR scans of boxes and cylinders by casting rays against each shape's exact surface.

A depth camera in a world of primitives needs no rasteriser: each pixel's depth is the nearest ray parameter at
which it meets a box (slab test) or a cylinder (a quadratic for the side, two planes for the caps). A shape is
tested only on the pixels of the rectangle its bounding box projects to, so a frame costs about the pixels times
the shapes stacked behind each, not the triangles of every visual in the world. Cylinders come out exact, not
tessellated.

A scan (:func:`cast_rays`) tests each beam against the shapes whose bounding ball the beam passes within, and
against the ground plane; a beam costs about the shapes near it, where ``rayTestBatch`` pays pybullet's per-call and
per-ray overheads (docs/benchmarks.md, "The exact LIDAR caster and the envs' own vector env").

Compiled with numba (cached on disk after the first call in a process).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Shape kinds in :func:`cast_depth`'s ``kinds``.
BOX, CYLINDER = 0, 1


@njit(cache=True, error_model="numpy")
def _box_hit(ex, ey, ez, dx, dy, dz, hx, hy, hz, near):
    """The smallest ray parameter >= near at which the ray e + t d meets the surface of the centred box with half
    extents h (inf if none)."""
    t_in, t_out = -np.inf, np.inf
    for e, d, h in ((ex, dx, hx), (ey, dy, hy), (ez, dz, hz)):
        if d == 0.0:
            if abs(e) > h:
                return np.inf
            continue
        t1, t2 = (-h - e) / d, (h - e) / d
        if t1 > t2:
            t1, t2 = t2, t1
        t_in, t_out = max(t_in, t1), min(t_out, t2)
    if t_in > t_out:
        return np.inf
    if t_in >= near:
        return t_in
    return t_out if t_out >= near else np.inf


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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
    corners = np.empty((8, 3))
    for k in range(n):
        nearest[k] = _image_rect(eye, axes, fx, fy, cx, cy, near, centres[k], rotations[k], halves[k], width, height,
                                 corners, rects[k])
    depth[:] = np.inf
    hit[:] = -1
    for k in np.argsort(nearest):  # nearest first: a pixel that already sees something nearer skips the test
        if nearest[k] >= far:
            break
        rot, h, c = rotations[k], halves[k], centres[k]
        # eye, forward, right and down in the shape's frame
        ex, ey, ez = _to_frame(rot, eye[0] - c[0], eye[1] - c[1], eye[2] - c[2])
        f0, f1, f2 = _to_frame(rot, axes[0, 0], axes[0, 1], axes[0, 2])
        r0, r1, r2 = _to_frame(rot, axes[1, 0], axes[1, 1], axes[1, 2])
        d0, d1, d2 = _to_frame(rot, axes[2, 0], axes[2, 1], axes[2, 2])
        i0, i1, j0, j1 = rects[k]
        box = kinds[k] == BOX
        for j in range(j0, j1 + 1):
            v = (j - cy) / fy
            for i in range(i0, i1 + 1):
                if depth[j, i] <= nearest[k]:
                    continue
                u = (i - cx) / fx
                dx, dy, dz = f0 + u * r0 + v * d0, f1 + u * r1 + v * d1, f2 + u * r2 + v * d2
                if box:
                    t = _box_hit(ex, ey, ez, dx, dy, dz, h[0], h[1], h[2], near)
                else:
                    t = _cylinder_hit(ex, ey, ez, dx, dy, dz, h[0], h[2], near)
                if t < depth[j, i] and t < far:
                    depth[j, i] = t
                    hit[j, i] = k
    for j in range(height):
        for i in range(width):
            if hit[j, i] < 0:
                depth[j, i] = 0.0


@njit(cache=True, error_model="numpy")
def _to_frame(rot, x, y, z):
    """The world vector (x, y, z) in the frame whose axes are the columns of ``rot``."""
    return (rot[0, 0] * x + rot[1, 0] * y + rot[2, 0] * z, rot[0, 1] * x + rot[1, 1] * y + rot[2, 1] * z,
            rot[0, 2] * x + rot[1, 2] * y + rot[2, 2] * z)


@njit(cache=True, error_model="numpy")
def _image_rect(eye, axes, fx, fy, cx, cy, near, centre, rot, h, width, height, corners, rect):
    """Set ``rect`` to the pixel rectangle (i0, i1, j0, j1), inclusive, that holds the projection of the shape's
    bounding box cut at the near plane (its corners in front of the plane and the points where its edges cross
    it); return the smallest depth of that cut box (inf, and an empty rectangle, when it lies behind the plane).
    ``corners``: (8, 3) scratch space."""
    # the box's centre and half axes in camera coordinates (rows: depth, right, down)
    rel = (centre[0] - eye[0], centre[1] - eye[1], centre[2] - eye[2])
    for corner in range(8):
        for row in range(3):
            value = axes[row, 0] * rel[0] + axes[row, 1] * rel[1] + axes[row, 2] * rel[2]
            for m in range(3):
                half = h[m] if corner & (1 << m) else -h[m]
                value += half * (axes[row, 0] * rot[0, m] + axes[row, 1] * rot[1, m] + axes[row, 2] * rot[2, m])
            corners[corner, row] = value
    i0, i1, j0, j1, nearest = width, -1, height, -1, np.inf
    for a in range(8):
        for b in (a, a | 1, a | 2, a | 4):  # the corner itself, then its edges to greater corners
            za, zb = corners[a, 0], corners[b, 0]
            if b == a:
                if za < near:
                    continue
                x, y, z = corners[a, 1], corners[a, 2], za
            elif (za < near) != (zb < near):
                s = (near - za) / (zb - za)
                x = corners[a, 1] + s * (corners[b, 1] - corners[a, 1])
                y = corners[a, 2] + s * (corners[b, 2] - corners[a, 2])
                z = near
            else:
                continue
            nearest = min(nearest, z)
            u, v = cx + fx * x / z, cy + fy * y / z
            i0, i1 = min(i0, int(math.floor(u))), max(i1, int(math.ceil(u)))
            j0, j1 = min(j0, int(math.floor(v))), max(j1, int(math.ceil(v)))
    rect[0], rect[1], rect[2], rect[3] = max(i0, 0), min(i1, width - 1), max(j0, 0), min(j1, height - 1)
    return nearest


@njit(cache=True, error_model="numpy")
def cast_rays(origin, axes, starts, ends, kinds, centres, rotations, halves, ground, fractions):
    """Fill ``fractions`` with where each segment ``start + s (end - start)``, s in [0, 1], first meets a surface.

    A segment that starts inside a shape does not see that shape (as Bullet's convex ray test); the ground is the
    plane z = 0, met from either side.

    Args:
        origin, axes: (3,) and (3, 3): the frame ``starts`` and ``ends`` are given in, world frame (its axes as
            columns).
        starts, ends: (m, 3) segment ends, metres.
        kinds, centres, rotations, halves: the shapes, as :func:`cast_depth` takes them.
        ground: whether the plane z = 0 is solid.
        fractions: (m,) output, the smallest such s, 1.0 for a segment that meets nothing.
    """
    m_rays, n = starts.shape[0], kinds.shape[0]
    world = np.empty((m_rays, 2, 3))
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for m in range(m_rays):
        for end, point in ((0, starts[m]), (1, ends[m])):
            for a in range(3):
                value = origin[a] + axes[a, 0] * point[0] + axes[a, 1] * point[1] + axes[a, 2] * point[2]
                world[m, end, a] = value
                lo[a], hi[a] = min(lo[a], value), max(hi[a], value)
    # the shapes whose bounding ball meets the scan's bounding box
    near = np.empty(n, dtype=np.int64)
    radius2 = np.empty(n)
    count = 0
    for k in range(n):
        h, c = halves[k], centres[k]
        r = math.sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2])  # holds a cylinder too: its halves are (r, r, h)
        if (c[0] + r < lo[0] or c[0] - r > hi[0] or c[1] + r < lo[1] or c[1] - r > hi[1] or c[2] + r < lo[2]
                or c[2] - r > hi[2]):
            continue
        near[count] = k
        radius2[count] = r * r
        count += 1
    for m in range(m_rays):
        sx, sy, sz = world[m, 0, 0], world[m, 0, 1], world[m, 0, 2]
        dx, dy, dz = world[m, 1, 0] - sx, world[m, 1, 1] - sy, world[m, 1, 2] - sz
        length2 = dx * dx + dy * dy + dz * dz
        best = 1.0
        if ground and dz != 0.0:
            s = -sz / dz
            if 0.0 <= s < best:
                best = s
        for j in range(count):
            k = near[j]
            c = centres[k]
            px, py, pz = c[0] - sx, c[1] - sy, c[2] - sz
            # the segment's point nearest the centre, within [0, best]: farther than the ball, no hit
            s = (px * dx + py * dy + pz * dz) / length2 if length2 > 0.0 else 0.0
            s = min(max(s, 0.0), best)
            qx, qy, qz = px - s * dx, py - s * dy, pz - s * dz
            if qx * qx + qy * qy + qz * qz > radius2[j]:
                continue
            rot, h = rotations[k], halves[k]
            ex, ey, ez = _to_frame(rot, -px, -py, -pz)
            ux, uy, uz = _to_frame(rot, dx, dy, dz)
            if kinds[k] == BOX:
                if abs(ex) <= h[0] and abs(ey) <= h[1] and abs(ez) <= h[2]:
                    continue
                t = _box_hit(ex, ey, ez, ux, uy, uz, h[0], h[1], h[2], 0.0)
            else:
                if ex * ex + ey * ey <= h[0] * h[0] and abs(ez) <= h[2]:
                    continue
                t = _cylinder_hit(ex, ey, ez, ux, uy, uz, h[0], h[2], 0.0)
            if t < best:
                best = t
        fractions[m] = best
