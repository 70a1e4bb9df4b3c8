"""python-fcl 0.7 signed distances against closed-form answers, with the request the collision layer uses.

Tolerances (errors measured on 0.7.0.11 are in the report of the change that added this file):

* sphere-sphere, touching: FCL has a closed-form sphere-sphere routine; the answer is exact up to rounding,
  so 1e-9 m.
* sphere-box, box-box, capsule-capsule: 1e-6 m. Pairs without a dedicated routine go through GJK (libccd),
  which stops on a tolerance near 1e-6 of the shapes' size, not at rounding; metre-sized shapes here.
* penetration: sphere-sphere is closed form (1e-6 m); box-box depth comes from EPA, which stops on a coarser
  tolerance, so 1e-4 m.
* far from the origin (1e4 m): a double's ulp there is ~2e-12 m, but GJK works on differences of world
  coordinates and loses more; see FAR_TOL.

Random rotations and offsets (seeded) keep every pose generic: FCL's GJK is wrong in exactly symmetric,
face-aligned box-box poses (documented by the xfail test at the end).
"""

from __future__ import annotations

import fcl
import numpy as np
import pytest

REQUEST = dict(enable_nearest_points=True, enable_signed_distance=True)  # as envs/collision/checker.py
TOL = 1e-6
FAR = np.array([1e4, -1e4, 1e4])
FAR_TOL = 1e-5
X, Z = np.eye(3)[0], np.eye(3)[2]


def signed_distance(geom_a, tf_a, geom_b, tf_b):
    """(signed distance, (2, 3) nearest points in the world frame, point 0 on ``geom_a``)."""
    result = fcl.DistanceResult()
    d = fcl.distance(fcl.CollisionObject(geom_a, tf_a), fcl.CollisionObject(geom_b, tf_b),
                     fcl.DistanceRequest(**REQUEST), result)
    return d, np.array(result.nearest_points)


def tf(rot, pos):
    return fcl.Transform(np.asarray(rot, float), np.asarray(pos, float))


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation(axis, angle):
    """Rotation by ``angle`` about the unit vector ``axis`` (Rodrigues)."""
    k = skew(axis)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def align(a, b):
    """Rotation taking unit vector ``a`` onto unit vector ``b`` (a != -b)."""
    k = skew(np.cross(a, b))
    return np.eye(3) + k + k @ k / (1.0 + float(np.dot(a, b)))


# ----------------------------------------------------------------------------------- case generators
# Each yields (FCL distance, closed-form distance, nearest points, extra data for witness checks).

def sphere_box_cases(rng, region, offset=np.zeros(3), n=50):
    """Sphere centre in the face (1 axis outside), edge (2) or corner (3) Voronoi region of a rotated box."""
    outside = {"face": 1, "edge": 2, "corner": 3}[region]
    for _ in range(n):
        half, rot, r = rng.uniform(0.1, 0.6, 3), random_rotation(rng), rng.uniform(0.05, 0.3)
        local = rng.uniform(-0.9, 0.9, 3) * half  # strictly inside the slab on the remaining axes
        axes = rng.permutation(3)[:outside]
        local[axes] = rng.choice([-1.0, 1.0], outside) * (half[axes] + rng.uniform(0.35, 0.8, outside))
        expected = np.linalg.norm(np.maximum(np.abs(local) - half, 0.0)) - r
        box_pos = offset + rng.uniform(-1.0, 1.0, 3)
        d, pts = signed_distance(fcl.Sphere(r), tf(np.eye(3), box_pos + rot @ local),
                                 fcl.Box(*2 * half), tf(rot, box_pos))
        yield d, expected, pts, (rot, box_pos, half)


def capsule_cases(rng, kind, offset=np.zeros(3), n=50):
    """Capsule pairs whose closest axis points are known: parallel, crossing skew, end to end."""
    for _ in range(n):
        frame = random_rotation(rng)
        u, n_, w = frame.T  # A's axis u; n_ is normal to both axes; B's axis is in the (w, u) plane
        ra, rb, la, lb = *rng.uniform(0.05, 0.3, 2), *rng.uniform(0.2, 1.0, 2)
        gap = rng.uniform(0.01, 0.5)
        if kind == "parallel":
            axis_b = u
            shift = (ra + rb + gap) * n_ + rng.uniform(-0.45, 0.45) * min(la, lb) * u
        elif kind == "skew":
            theta = rng.uniform(0.2, np.pi - 0.2)
            axis_b = np.cos(theta) * u + np.sin(theta) * w
            # closest axis points at +a on A and -b on B, inside both segments: axis distance is exactly
            # the n_ component
            a, b = rng.uniform(-0.45, 0.45) * la, rng.uniform(-0.45, 0.45) * lb
            shift = (ra + rb + gap) * n_ + a * u + b * axis_b
        else:  # end to end along A's axis
            axis_b = u * rng.choice([-1.0, 1.0])
            shift = (la / 2 + lb / 2 + ra + rb + gap) * u
        centre = offset + rng.uniform(-1.0, 1.0, 3)
        d, pts = signed_distance(fcl.Capsule(ra, la), tf(align(Z, u), centre),
                                 fcl.Capsule(rb, lb), tf(align(Z, axis_b), centre + shift))
        yield d, gap, pts, None


def box_box_cases(rng, kind, offset=np.zeros(3), n=50):
    """Box B beyond A's +x face by ``gap``, presenting a face, an edge or a corner; both in a random frame."""
    for _ in range(n):
        ha, hb = rng.uniform(0.2, 0.6, 3), rng.uniform(0.05, 0.3, 3)
        gap = rng.uniform(0.01, 0.5)
        if kind == "face":  # parallel faces
            rot_b, reach = np.eye(3), hb[0]
        elif kind == "edge":  # Rz turns B's (+x, +y) vertical edge to point along -x at A's face
            rot_b, reach = rotation(Z, np.pi - np.arctan2(hb[1], hb[0])), np.hypot(hb[0], hb[1])
        else:  # corner: B's (+, +, +) corner turned to point along -x, random spin about x
            reach = np.linalg.norm(hb)
            rot_b = rotation(X, rng.uniform(0, 2 * np.pi)) @ align(hb / reach, -X)
        # lateral offset keeps B's nearest feature in front of A's face, generic in y and z
        local = np.array([ha[0] + gap + reach, *rng.uniform(-0.8, 0.8, 2) * ha[1:]])
        frame, pos = random_rotation(rng), offset + rng.uniform(-1.0, 1.0, 3)
        d, pts = signed_distance(fcl.Box(*2 * ha), tf(frame, pos),
                                 fcl.Box(*2 * hb), tf(frame @ rot_b, pos + frame @ local))
        yield d, gap, pts, None
