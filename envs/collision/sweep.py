"""Swept collision of a rigid shape over one step, rotation included: the audit behind ``info["tunneling"]``.

Between two checks a shape is taken to move on the screw motion from its previous pose to its pose now (a constant
twist): a link turning about one joint axis moves exactly so, and a shape that only translates moves in a straight
line. :func:`time_of_impact` runs conservative advancement on that motion with FCL's exact distance and witness
points: both shapes are convex, so the plane through the shape's witness point, normal to the gap, has the whole
shape behind it, and the shape cannot come within the reach before one of its points has crossed the gap less the
reach along that normal. No point moves along the normal faster than the twist's translation along it plus ``|w| r``
(``w`` the rotation, ``r`` the shape's radius about its origin), so advancing the time by the gap over that rate can
never step past a contact; a shape sliding along an obstacle advances in one step. It stops at the first time the
shape comes within the reach, or at the end of the step. FCL's own ``continuousCollide`` sweeps
translation only, and its conservative advancement on boxes misses some fast passes through thin walls
(docs/hard-cases.md, "Tunneling").
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
def _skew(w):  # pragma: no cover (compiled)
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


@njit(cache=True)
def _so3_exp(w):  # pragma: no cover (compiled)
    """Rotation matrix of the rotation vector ``w`` (Rodrigues)."""
    angle = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    k = _skew(w)
    if angle < 1e-9:
        return np.eye(3) + k
    return np.eye(3) + math.sin(angle) / angle * k + (1.0 - math.cos(angle)) / angle**2 * (k @ k)


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
def _left_jacobian(w):  # pragma: no cover (compiled)
    """SO(3)'s left Jacobian V(w): the translation of exp of the twist (w, v) is V(w) v."""
    angle = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    k = _skew(w)
    if angle < 1e-6:
        return np.eye(3) + 0.5 * k + (k @ k) / 6.0
    return np.eye(3) + (1.0 - math.cos(angle)) / angle**2 * k + (angle - math.sin(angle)) / angle**3 * (k @ k)


@njit(cache=True)
def _twist(r0, p0, r1, p1):  # pragma: no cover (compiled)
    """The twist (w, v), in the frame of pose 0, of the screw motion from pose 0 to pose 1."""
    w = _so3_log(r0.T @ r1)
    return w, np.linalg.solve(_left_jacobian(w), r0.T @ (p1 - p0))


@njit(cache=True)
def _pose(r0, p0, w, v, t):  # pragma: no cover (compiled)
    """(rotation, position) at time ``t`` of the screw motion with twist (w, v) from pose 0."""
    wt = t * w
    return r0 @ _so3_exp(wt), p0 + r0 @ (_left_jacobian(wt) @ (t * v))


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
        """A function of a world-frame unit direction ``n``: the fastest any point within ``radius`` of the shape's
        origin moves along ``n`` at any time of the motion, metres per step. The translation rate turns with the
        shape about the rotation axis: its part along the axis keeps its direction, the rest may point anywhere
        in the plane normal to the axis."""
        angle = float(np.linalg.norm(self.w))
        spin = angle * radius
        if angle == 0.0:
            along = self._r0 @ self.v
            return lambda n: abs(float(n @ along)) + spin
        axis = self._r0 @ (self.w / angle)
        v_axis = float(self.v @ (self.w / angle))
        v_plane = math.sqrt(max(float(self.v @ self.v) - v_axis * v_axis, 0.0))

        def rate(n: np.ndarray) -> float:
            n_axis = float(n @ axis)
            return abs(n_axis * v_axis) + math.sqrt(max(1.0 - n_axis * n_axis, 0.0)) * v_plane + spin

        return rate

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(rotation, position) at time ``t``."""
        return _pose(self._r0, self._p0, self.w, self.v, t)


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
        rate = approach(gap / np.linalg.norm(gap))
        if rate <= 0.0:
            return None
        t += (d - reach) / rate
        if t > 1.0:
            return None
    return t  # still closing in after every advance: counted as an impact, which errs on the safe side
