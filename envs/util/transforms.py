"""Rigid-transform helpers on plain numpy arrays, and 3x3 matrix-vector products on Python floats for the per-tick
loops where numpy's per-call cost outweighs three dot products. Quaternions are (x, y, z, w), as pybullet writes
them; a matrix as floats is its 9 entries row by row (pybullet's ``getMatrixFromQuaternion`` order)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeVar

import numpy as np

Real = TypeVar("Real", float, np.ndarray)
Vector3 = tuple[float, float, float]


def times(m: Sequence[float], v: Sequence[float]) -> Vector3:
    """``M v`` for a 3x3 matrix ``m`` given as 9 floats row by row."""
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z,
            m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)


def times_transposed(m: Sequence[float], v: Sequence[float]) -> Vector3:
    """``M^T v`` for a 3x3 matrix ``m`` given as 9 floats row by row: a world vector in the body frame, for ``m``
    a body's rotation."""
    x, y, z = v
    return (m[0] * x + m[3] * y + m[6] * z,
            m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z)


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices from unit quaternions: (4,) -> (3, 3) or (n, 4) -> (n, 3, 3)."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:  # Python floats: the same arithmetic, without numpy's cost per operation on 0-d arrays
        return np.array(_matrix_entries(*q.tolist())).reshape(3, 3)
    entries = _matrix_entries(q[..., 0], q[..., 1], q[..., 2], q[..., 3])
    return np.stack(entries, axis=-1).reshape(q.shape[:-1] + (3, 3))


def _matrix_entries(x: Real, y: Real, z: Real, w: Real) -> tuple[Real, ...]:
    """The rotation matrix of quaternion (x, y, z, w), row by row."""
    return (
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    )


def yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation by ``yaw`` radians about +z."""
    return (0.0, 0.0, float(np.sin(yaw / 2)), float(np.cos(yaw / 2)))


def quat_multiply(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, float, float]:
    """The rotation ``a`` after ``b``, quaternions (x, y, z, w) as pybullet orders them."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def rpy_quat(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Quaternion (x, y, z, w) of URDF fixed-axis roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.array(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ]
    )
