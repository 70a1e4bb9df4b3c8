"""python-fcl 0.7 distances against closed-form answers.

The collision layer's ``signed_distance`` (envs/collision/distance.py) asks without the signed flag first and
with it only in overlap, because with signed distance on FCL 0.7 skips its closed-form primitive routines and
runs libccd GJK/EPA for every shape pair (FCL issue #294); python-fcl exposes no ``distance_tolerance``.
FCL minus the closed form, 20000 random separated poses per case on 0.7.0.11, metres:

* signed request: median 1e-8..5e-7 but long tails: 4e-3 sphere-sphere, 1e-3 sphere-box, 2e-2 capsule end
  to end and 0.3 crossing capsules (GJK stalls, ~1 pose in 1e4; strict xfail below). Never below the closed
  form (the witness points lie on the shapes). Box-box is exact, ~1e-15: GJK on polytopes ends on vertices.
  GJK_TOL = 1e-3 is ~6x the worst error of the seeded poses here (1.6e-4), not a bound on every pose.
* unsigned request (closed-form routines): <= 2e-13 at the origin and 6e-12 at 1e4 m, where a double's ulp
  is 1.8e-12 -> EXACT_TOL = 1e-10 for both. The signed request is no worse at 1e4 m than at the origin.
* EPA depth: sphere-sphere <= 9.9e-7 (EPA stops near 1e-6) -> EPA_TOL = 1e-5; box-box ~4e-16 -> 1e-9.

Poses are random (seeded) so that none is exactly symmetric: in such box-box poses FCL's GJK is wrong
(strict xfail below, for both requests).
"""

from __future__ import annotations

import fcl
import numpy as np
import pytest

from clutter_gym.collision.distance import signed_distance

EXACT_TOL = 1e-10  # closed-form routines, also at 1e4 m
GJK_TOL = 1e-3  # signed request, separated curved shapes, seeded poses only
EPA_TOL = 1e-5  # signed request, sphere-sphere penetration depth
FAR = np.array([1e4, -1e4, 1e4])
X, Z = np.eye(3)[0], np.eye(3)[2]
N = 200  # random poses per case


def project_distance(geom_a, tf_a, geom_b, tf_b):
    """The collision layer's :func:`signed_distance` (unsigned request first, signed only in overlap)."""
    d, result = signed_distance(fcl.CollisionObject(geom_a, tf_a), fcl.CollisionObject(geom_b, tf_b))
    return d, np.array(result.nearest_points)


def fcl_distance(geom_a, tf_a, geom_b, tf_b, signed=True):
    """Raw FCL with one request: (distance, (2, 3) world-frame nearest points, point 0 on ``geom_a``)."""
    request = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=signed)
    result = fcl.DistanceResult()
    d = fcl.distance(fcl.CollisionObject(geom_a, tf_a), fcl.CollisionObject(geom_b, tf_b), request, result)
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


# ------------------------------ separated pairs: return ((geom_a, tf_a, geom_b, tf_b), closed form, witness info)
def sphere_sphere(rng, kind, offset):
    c1, (r1, r2), u = offset + rng.uniform(-1, 1, 3), rng.uniform(0.05, 0.5, 2), random_rotation(rng)[:, 0]
    c2 = c1 + (r1 + r2 + rng.uniform(0.01, 1.0)) * u
    return (fcl.Sphere(r1), tf(np.eye(3), c1), fcl.Sphere(r2), tf(np.eye(3), c2)), \
        np.linalg.norm(c2 - c1) - r1 - r2, (c1, r1, c2, r2)


def sphere_box(rng, kind, offset):
    """Sphere centre in the face (1 axis beyond the box), edge (2) or corner (3) region of a rotated box."""
    outside = {"face": 1, "edge": 2, "corner": 3}[kind]
    half, rot, r = rng.uniform(0.1, 0.6, 3), random_rotation(rng), rng.uniform(0.05, 0.3)
    local = rng.uniform(-0.9, 0.9, 3) * half  # strictly within the slab on the other axes
    axes = rng.permutation(3)[:outside]
    local[axes] = rng.choice([-1.0, 1.0], outside) * (half[axes] + rng.uniform(0.35, 0.8, outside))
    pos = offset + rng.uniform(-1, 1, 3)
    return (fcl.Sphere(r), tf(np.eye(3), pos + rot @ local), fcl.Box(*2 * half), tf(rot, pos)), \
        np.linalg.norm(np.maximum(np.abs(local) - half, 0.0)) - r, (rot, pos, half)


def capsule_capsule(rng, kind, offset):
    """Axes parallel, crossing (skew) or end to end; the closest axis points are known by construction."""
    u, n, w = random_rotation(rng).T  # A's axis u; n is normal to both axes; B's axis lies in the (u, w) plane
    (ra, rb), (la, lb), gap = rng.uniform(0.05, 0.3, 2), rng.uniform(0.2, 1.0, 2), rng.uniform(0.01, 0.5)
    if kind == "parallel":  # axial overlap, so the axes' distance is ra + rb + gap
        v, shift = u, (ra + rb + gap) * n + rng.uniform(-0.45, 0.45) * min(la, lb) * u
    elif kind == "skew":  # closest axis points at +a on A and -b on B, inside both segments
        theta = rng.uniform(0.2, np.pi - 0.2)
        v = np.cos(theta) * u + np.sin(theta) * w
        shift = (ra + rb + gap) * n + rng.uniform(-0.45, 0.45) * la * u + rng.uniform(-0.45, 0.45) * lb * v
    else:  # end to end along A's axis
        v, shift = u * rng.choice([-1.0, 1.0]), (la / 2 + lb / 2 + ra + rb + gap) * u
    centre = offset + rng.uniform(-1, 1, 3)
    return (fcl.Capsule(ra, la), tf(align(Z, u), centre), fcl.Capsule(rb, lb), tf(align(Z, v), centre + shift)), \
        gap, None


def box_box(rng, kind, offset):
    """B beyond A's +x face by ``gap``, presenting a face, an edge or a corner; both in a random frame."""
    ha, hb, gap = rng.uniform(0.2, 0.6, 3), rng.uniform(0.05, 0.3, 3), rng.uniform(0.01, 0.5)
    if kind == "face":
        rot_b, reach = np.eye(3), hb[0]
    elif kind == "edge":  # B's (+x, +y) vertical edge turned about z to point along -x
        rot_b, reach = rotation(Z, np.pi - np.arctan2(hb[1], hb[0])), np.hypot(hb[0], hb[1])
    else:  # B's (+, +, +) corner turned to point along -x (half diagonal), random spin about x
        reach = np.linalg.norm(hb)
        rot_b = rotation(X, rng.uniform(0, 2 * np.pi)) @ align(hb / reach, -X)
    local = np.array([ha[0] + gap + reach, *rng.uniform(-0.8, 0.8, 2) * ha[1:]])  # in front of A's face
    frame, pos = random_rotation(rng), offset + rng.uniform(-1, 1, 3)
    return (fcl.Box(*2 * ha), tf(frame, pos), fcl.Box(*2 * hb), tf(frame @ rot_b, pos + frame @ local)), gap, None


CASES = [(sphere_sphere, "-")] + [(sphere_box, k) for k in ("face", "edge", "corner")] \
    + [(capsule_capsule, k) for k in ("parallel", "skew", "end")] + [(box_box, k) for k in ("face", "edge", "corner")]
EACH_OFFSET = pytest.mark.parametrize("offset", [np.zeros(3), FAR], ids=["origin", "far"])
EACH_CASE = pytest.mark.parametrize("make, kind", CASES, ids=[f"{m.__name__}-{k}" for m, k in CASES])


def check_witnesses(make, d, pts, info):
    assert np.linalg.norm(pts[0] - pts[1]) == pytest.approx(d, abs=1e-9)
    if make is sphere_sphere:  # on each surface, along the centre line
        c1, r1, c2, r2 = info
        u = (c2 - c1) / np.linalg.norm(c2 - c1)
        np.testing.assert_allclose(pts, [c1 + r1 * u, c2 - r2 * u], atol=1e-6)
    if make is sphere_box:  # point 1 on the box surface
        rot, pos, half = info
        assert np.max(np.abs(rot.T @ (pts[1] - pos)) / half) == pytest.approx(1.0, abs=1e-6)


@EACH_OFFSET
@EACH_CASE
def test_project_distance_is_exact(make, kind, offset):
    """The layer's request (unsigned first: FCL's primitive routines) matches the closed form to rounding,
    witnesses included."""
    rng = np.random.default_rng(1)
    for _ in range(N):
        pair, exact, info = make(rng, kind, offset)
        d, pts = project_distance(*pair)
        assert d == pytest.approx(exact, abs=EXACT_TOL)
        check_witnesses(make, d, pts, info)


@EACH_OFFSET
@EACH_CASE
def test_fcl_signed_request_within_gjk_bound(make, kind, offset):
    """Raw signed request (GJK, what the layer avoids when separated): never below the closed form, typically
    within 1e-6, within GJK_TOL on these poses."""
    rng, errors = np.random.default_rng(1), []
    for _ in range(N):
        pair, exact, info = make(rng, kind, offset)
        d, pts = fcl_distance(*pair)
        errors.append(d - exact)
        assert np.linalg.norm(pts[0] - pts[1]) == pytest.approx(d, abs=1e-9)
        if make is sphere_box:
            check_witnesses(make, d, pts, info)
    tol = EXACT_TOL if make is box_box else GJK_TOL  # GJK on polytopes terminates exactly
    assert min(errors) >= -EXACT_TOL and max(errors) <= tol
    assert np.median(errors) <= 1e-6


@pytest.mark.parametrize("pair", [
    (fcl.Sphere(0.5), tf(np.eye(3), [0, 0, 0]), fcl.Sphere(0.75), tf(np.eye(3), [1.25, 0, 0])),
    (fcl.Box(1, 1, 1), tf(np.eye(3), [0, 0, 0]), fcl.Box(0.5, 0.5, 0.5), tf(np.eye(3), [0.75, 0.1, 0.2])),
    (fcl.Sphere(0.25), tf(np.eye(3), [0.75, 0.125, -0.0625]), fcl.Box(1, 1, 1), tf(np.eye(3), [0, 0, 0])),
], ids=["sphere-sphere", "box-box", "sphere-box"])
def test_touching_is_zero(pair):
    """Exactly touching (dyadic and axis-aligned, so exact in floating point)."""
    assert project_distance(*pair)[0] == pytest.approx(0.0, abs=1e-9)


def test_penetration_depth():
    """Signed request: -depth; sphere-sphere via EPA (EPA_TOL), box-box overlapping by 0.05 along a rotated x."""
    rng = np.random.default_rng(2)
    for _ in range(50):
        c1, (r1, r2), u = rng.uniform(-1, 1, 3), rng.uniform(0.1, 0.5, 2), random_rotation(rng)[:, 0]
        c2 = c1 + rng.uniform(0.05, 0.95) * (r1 + r2) * u
        d, _ = project_distance(fcl.Sphere(r1), tf(np.eye(3), c1), fcl.Sphere(r2), tf(np.eye(3), c2))
        assert d == pytest.approx(np.linalg.norm(c2 - c1) - r1 - r2, abs=EPA_TOL)
        ha, hb, frame, pos = rng.uniform(0.2, 0.6, 3), rng.uniform(0.1, 0.3, 3), random_rotation(rng), c1
        local = np.array([ha[0] + hb[0] - 0.05, *rng.uniform(-0.5, 0.5, 2) * np.clip(ha[1:] - hb[1:], 0, None)])
        d, _ = project_distance(fcl.Box(*2 * ha), tf(frame, pos), fcl.Box(*2 * hb), tf(frame, pos + frame @ local))
        assert d == pytest.approx(-0.05, abs=1e-9)  # EPA on polytopes: ~4e-16 measured


def stalled_capsules():
    """Crossing capsules built like capsule_capsule('skew'), 0.17 m apart; about 1 random pose in 1e4 makes the
    raw signed request stall like this one."""
    u, n, w = rotation(np.array([0.0, 9, -8]) / np.sqrt(145), np.deg2rad(347)).T
    v = np.cos(np.deg2rad(56)) * u + np.sin(np.deg2rad(56)) * w
    shift = (0.24 + 0.19 + 0.17) * n + 0.14 * u - 0.05 * v
    return (fcl.Capsule(0.24, 0.6), tf(align(Z, u), [0, 0, 0]), fcl.Capsule(0.19, 0.4), tf(align(Z, v), shift))


def test_the_layer_is_exact_where_the_signed_request_stalls():
    assert project_distance(*stalled_capsules())[0] == pytest.approx(0.17, abs=EXACT_TOL)


@pytest.mark.xfail(strict=True, reason="FCL GJK stall under signed distance: 0.4897 for a 0.17 gap (unsigned: exact)")
def test_capsule_gjk_stall():
    assert fcl_distance(*stalled_capsules())[0] == pytest.approx(0.17, abs=GJK_TOL)


@pytest.mark.xfail(strict=True, reason="FCL GJK: exactly symmetric face-aligned boxes give a vertex-vertex distance")
def test_symmetric_box_box():
    """Gaps 0.4 (x) and 0.3 (y): 0.5 exactly; FCL gives 0.7071. Offsets >= 1e-4 make it disappear."""
    pair = (fcl.Box(0.4, 0.6, 0.8), tf(np.eye(3), [0, 0, 0]), fcl.Box(0.2, 0.2, 0.2), tf(np.eye(3), [0.7, 0.7, 0]))
    assert project_distance(*pair)[0] == pytest.approx(0.5, abs=1e-6)
