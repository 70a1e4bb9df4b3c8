"""Swept collision of a rigid shape over one step, rotation included: the audit behind ``info["tunneling"]``.

Between two checks a shape is taken to move on the screw motion from its previous pose to its pose now (a constant
twist): a link turning about one joint axis moves exactly so, and a shape that only translates moves in a straight
line. :func:`time_of_impact` runs conservative advancement on that motion with FCL's exact distance and witness
points: both shapes are convex, so the plane through the shape's witness point, normal to the gap, has the whole
shape behind it, and the shape cannot come within the reach before one of its points has crossed the gap less the
reach along that normal. No point moves along the normal faster than the twist's translation along it plus ``|w| r``
(``w`` the rotation, ``r`` the shape's radius about its origin) times the sine of the normal's angle to the rotation
axis, so advancing the time by the gap over that rate can never step past a contact; a shape sliding along an
obstacle advances in one step. It stops at the first time the shape comes within the reach, or at the end of the
step. FCL's own ``continuousCollide`` sweeps translation only, and its conservative advancement on boxes misses some
fast passes through thin walls (docs/hard-cases.md, "Tunneling").
"""

from __future__ import annotations

import math

import fcl
import numpy as np
from numba import njit

#: advancement steps before a sweep that has not found its way past the obstacle counts as a hit (conservative)
MAX_ADVANCES = 64
#: metres: a distance within this of the reach is an impact (advancing by the exact remaining distance closes in on a
#: contact geometrically; a micrometre is far below any contact tolerance)
CLOSE_ENOUGH = 1e-6
_DISTANCE = fcl.DistanceRequest(enable_nearest_points=True)


@njit(cache=True)
def _exp_and_jacobian(w):  # pragma: no cover (compiled)
    """(exp of the rotation vector ``w``, SO(3)'s left Jacobian V(w)): Rodrigues, and the translation of the
    exponential of the twist (w, v) is V(w) v; written out for 3x3, which BLAS calls would cost more than."""
    angle = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if angle < 1e-6:  # the series: exp = I + K + K^2 / 2, V = I + K / 2 + K^2 / 6
        a, b, c = 1.0, 0.5, 1.0 / 6.0
    else:
        a, b, c = math.sin(angle) / angle, (1.0 - math.cos(angle)) / angle**2, (angle - math.sin(angle)) / angle**3
    k = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    kk = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            kk[i, j] = k[i, 0] * k[0, j] + k[i, 1] * k[1, j] + k[i, 2] * k[2, j]
    rotation = np.empty((3, 3))
    jacobian = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            eye = 1.0 if i == j else 0.0
            rotation[i, j] = eye + a * k[i, j] + b * kk[i, j]
            jacobian[i, j] = eye + b * k[i, j] + c * kk[i, j]
    return rotation, jacobian


@njit(cache=True)
def _so3_log(rotation):  # pragma: no cover (compiled)
    """Rotation vector of a rotation matrix, angle in [0, pi]."""
    cos_angle = min(max((rotation[0, 0] + rotation[1, 1] + rotation[2, 2] - 1.0) / 2.0, -1.0), 1.0)
    angle = math.acos(cos_angle)
    axis = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0], rotation[1, 0] - rotation[0, 1]])
    if angle < 1e-9:
        return 0.5 * axis
    if math.pi - angle > 1e-6:
        return angle / (2.0 * math.sin(angle)) * axis
    # near a half turn the antisymmetric part vanishes: the axis is the column of R + I with the largest norm
    columns = rotation + np.eye(3)
    best, norm = 0, 0.0
    for c in range(3):
        n = math.sqrt(columns[0, c] ** 2 + columns[1, c] ** 2 + columns[2, c] ** 2)
        if n > norm:
            best, norm = c, n
    return angle * columns[:, best] / norm


@njit(cache=True)
def _twist(r0, p0, r1, p1):  # pragma: no cover (compiled)
    """The twist (w, v), in the frame of pose 0, of the screw motion from pose 0 to pose 1."""
    w = _so3_log(r0.T @ r1)
    return w, np.linalg.solve(_exp_and_jacobian(w)[1], r0.T @ (p1 - p0))


@njit(cache=True)
def _pose(r0, p0, w, v, t):  # pragma: no cover (compiled)
    """(rotation, position) at time ``t`` of the screw motion with twist (w, v) from pose 0."""
    turn, jacobian = _exp_and_jacobian(t * w)
    rotation = np.empty((3, 3))
    local = np.empty(3)  # the displacement in the frame of pose 0
    position = np.empty(3)
    for i in range(3):
        for j in range(3):
            rotation[i, j] = r0[i, 0] * turn[0, j] + r0[i, 1] * turn[1, j] + r0[i, 2] * turn[2, j]
        local[i] = t * (jacobian[i, 0] * v[0] + jacobian[i, 1] * v[1] + jacobian[i, 2] * v[2])
    for i in range(3):
        position[i] = p0[i] + r0[i, 0] * local[0] + r0[i, 1] * local[1] + r0[i, 2] * local[2]
    return rotation, position


@njit(cache=True)
def _path(r0, p0, w, v, offset, n):  # pragma: no cover (compiled)
    """(n, 3) world positions of the body point ``offset`` at n evenly spaced times from 0 to 1."""
    out = np.empty((n, 3))
    for k in range(n):
        rotation, position = _pose(r0, p0, w, v, k / (n - 1))
        for i in range(3):
            out[k, i] = (position[i] + rotation[i, 0] * offset[0] + rotation[i, 1] * offset[1]
                         + rotation[i, 2] * offset[2])
    return out


def _cross(a, b) -> np.ndarray:
    """``a x b`` of two 3-vectors (numpy's ``cross`` costs more than the arithmetic at this size)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


class ScrewMotion:
    """The constant-twist motion from pose 0 to pose 1 (rotation matrices, positions in metres), for t in [0, 1].

    Attributes:
        w, v: the twist in the frame of pose 0: rotation vector (rad) and translation rate (m per step).
    """

    def __init__(self, rotation0: np.ndarray, position0: np.ndarray, rotation1: np.ndarray,
                 position1: np.ndarray) -> None:
        self._r0 = np.ascontiguousarray(rotation0, dtype=float)
        self._p0 = np.ascontiguousarray(position0, dtype=float)
        self.w, self.v = _twist(self._r0, self._p0, np.ascontiguousarray(rotation1, dtype=float),
                                np.ascontiguousarray(position1, dtype=float))

    def travel(self, radius: float) -> float:
        """The farthest any point within ``radius`` of the shape's origin travels over the whole motion, metres."""
        return float(np.linalg.norm(self.v) + np.linalg.norm(self.w) * radius)

    def approach_rates(self, radius: float):
        """A function of a world-frame unit direction ``n`` and a time ``t``: the fastest any point within
        ``radius`` of the shape's origin moves along ``n`` (signed: negative moves away) at any time from ``t`` on,
        metres per step. The rotation turns about a fixed axis by ``|w|`` over the step, keeping every angle to the
        axis: the translation rate's part along the axis keeps its direction, the rest turns within the plane normal
        to the axis by ``|w| (1 - t)`` from where it is at ``t``, and the turning moves a point along ``n`` at most
        ``|w| radius`` times the sine of ``n``'s angle to the axis."""
        angle = math.sqrt(float(self.w @ self.w))
        if angle == 0.0:
            along = self._r0 @ self.v
            return lambda n, t: float(n @ along)
        spin = angle * radius
        axis_body = self.w / angle
        axis = self._r0 @ axis_body
        v_axis = float(self.v @ axis_body)
        plane = self._r0 @ (self.v - v_axis * axis_body)  # the translation rate's in-plane part at t = 0, world
        v_plane = math.sqrt(float(plane @ plane))
        if v_plane > 0.0:
            first = plane / v_plane
        else:  # no in-plane translation: any direction of the plane will do
            first = _cross(axis, (1.0, 0.0, 0.0) if abs(axis[0]) < 0.9 else (0.0, 1.0, 0.0))
            first /= math.sqrt(float(first @ first))
        second = _cross(axis, first)  # the in-plane part turns from first towards second

        def rate(n: np.ndarray, t: float) -> float:
            n_axis = float(n @ axis)
            sine = math.sqrt(max(1.0 - n_axis * n_axis, 0.0))
            # n's in-plane direction at angle beta from first; the translation's turns from angle*t to angle
            beta = math.atan2(float(n @ second), float(n @ first))
            lo, hi = angle * t, angle
            ahead = (beta - lo) % (2.0 * math.pi)
            cosine = 1.0 if ahead <= hi - lo else max(math.cos(beta - lo), math.cos(beta - hi))
            return n_axis * v_axis + sine * (v_plane * cosine + spin)

        return rate

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(rotation, position) at time ``t``."""
        return _pose(self._r0, self._p0, self.w, self.v, t)

    def path(self, offset: np.ndarray, n: int) -> np.ndarray:
        """(n, 3) world positions of the point ``offset`` (in the shape's frame) at n evenly spaced times, 0 and 1
        included; between two of them it travels at most ``travel(|offset|) / (n - 1)``."""
        return _path(self._r0, self._p0, self.w, self.v, np.ascontiguousarray(offset, dtype=float), n)


def time_of_impact(shape: fcl.CollisionObject, radius: float, motion: ScrewMotion, obstacle: fcl.CollisionObject,
                   reach: float) -> float | None:
    """The first time in [0, 1] at which ``shape`` on ``motion`` comes within ``reach`` metres of ``obstacle``, to
    within :data:`CLOSE_ENOUGH`; None when it never does.

    Args:
        shape: the moving shape, convex (FCL moves it: its transform is left at the last time tried).
        radius: the shape's radius about its origin, metres.
        motion: the shape's origin and axes over the step.
        obstacle: a fixed convex obstacle.
        reach: metres; a distance at or below it is an impact (a contact tolerance plus any padding).
    """
    approach = motion.approach_rates(radius)
    t = 0.0
    for _ in range(MAX_ADVANCES):
        rotation, position = motion.pose(t)
        shape.setRotation(rotation)
        shape.setTranslation(position)
        result = fcl.DistanceResult()
        d = fcl.distance(shape, obstacle, _DISTANCE, result)
        if d <= reach + CLOSE_ENOUGH:
            return t
        gap = np.asarray(result.nearest_points[1]) - np.asarray(result.nearest_points[0])
        rate = approach(gap / math.sqrt(float(gap @ gap)), t)
        if rate <= 0.0:  # nothing of the shape moves towards the obstacle from here on
            return None
        t += (d - reach) / rate
        if t > 1.0:
            return None
    return t  # still closing in after every advance: counted as an impact, which errs on the safe side
