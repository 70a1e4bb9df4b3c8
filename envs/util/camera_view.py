"""Where world points land in a look-at camera's frame, and where to put such a camera, on plain numpy arrays.

The matrices are the ones pybullet's ``computeViewMatrix`` (gluLookAt, z up) and ``computeProjectionMatrixFOV``
(an OpenGL perspective) build, so a point projected here lands on the pixel where ``getCameraImage`` (TinyRenderer)
draws it (tests/util/test_camera_view.py holds them to pybullet's). Pixel coordinates are (column, row), row 0 at the
top, pixel (row r, column c) at (c, r), as numpy indexes an image.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

UP = (0.0, 0.0, 1.0)
NEAR, FAR = 0.05, 50.0  # metres: the clip planes of the rgb_array frame
FOV_DEG = 60.0  # the rgb_array frame's vertical field of view, degrees


def look_at(eye: Sequence[float], target: Sequence[float], up: Sequence[float] = UP) -> np.ndarray:
    """The 4x4 world-to-camera matrix of a camera at ``eye`` looking at ``target`` with ``up`` upwards (gluLookAt:
    the camera looks along its -z)."""
    eye, target, up = (np.asarray(v, dtype=float) for v in (eye, target, up))
    forward = _unit(target - eye)
    side = _unit(np.cross(forward, up))
    true_up = np.cross(side, forward)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = side, true_up, -forward
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def perspective(fov_deg: float, aspect: float, near: float = NEAR, far: float = FAR) -> np.ndarray:
    """The 4x4 OpenGL projection matrix of a vertical field of view ``fov_deg`` degrees and width / height
    ``aspect``."""
    f = 1.0 / math.tan(math.radians(fov_deg) / 2.0)
    return np.array([
        [f / aspect, 0.0, 0.0, 0.0],
        [0.0, f, 0.0, 0.0],
        [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
        [0.0, 0.0, -1.0, 0.0],
    ])


@dataclass(frozen=True, slots=True)
class CameraView:
    """A look-at camera with its image size: everything needed to place world points in its frames.

    Attributes:
        eye, target: world frame, metres.
        width, height: image size in pixels.
        fov_deg: vertical field of view, degrees.
    """

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    width: int
    height: int
    fov_deg: float = FOV_DEG

    def normalised(self, points: np.ndarray | Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
        """Normalised device coordinates (n, 2) of world points (n, 3), x right and y up, in [-1, 1] across the
        frame, and whether each lies in front of the camera (a point behind it has no place in the frame: its
        coordinates are those of its mirror image and must not be drawn)."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        homogeneous = np.hstack([p, np.ones((len(p), 1))])
        clip = homogeneous @ (perspective(self.fov_deg, self.width / self.height) @ look_at(self.eye, self.target)).T
        w = clip[:, 3]
        safe = np.where(np.abs(w) > 1e-12, w, 1e-12)
        return clip[:, :2] / safe[:, None], w > NEAR

    def project(self, points: np.ndarray | Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (n, 2), (column, row), of world points (n, 3), and whether each lies in front of the
        camera (see :meth:`normalised`). TinyRenderer samples pixel (row r, column c) at the viewport point
        (c, height - 1 - r), the viewport spanning [0, width] x [0, height]."""
        ndc, in_front = self.normalised(points)
        col = (ndc[:, 0] + 1.0) * 0.5 * self.width
        row = (1.0 - ndc[:, 1]) * 0.5 * self.height - 1.0
        return np.stack([col, row], axis=1), in_front

    def depth(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        """Distance of each point (n, 3) in front of the camera along its optical axis, metres (negative behind)."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        forward = _unit(np.subtract(self.target, self.eye))
        return (p - np.asarray(self.eye)) @ forward

    def pixels_per_metre(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        """How many pixels one metre across spans at each point's depth (0 behind the camera)."""
        focal = 0.5 * self.height / math.tan(math.radians(self.fov_deg) / 2.0)
        d = self.depth(points)
        return np.where(d > NEAR, focal / np.maximum(d, NEAR), 0.0)


def orbit_angles(eye: Sequence[float], target: Sequence[float]) -> tuple[float, float, float]:
    """(distance in metres, yaw and pitch in degrees) that point pybullet's GUI camera
    (``resetDebugVisualizerCamera``) from ``eye`` at ``target``."""
    offset = np.subtract(target, eye).astype(float)
    distance = float(np.linalg.norm(offset))
    fx, fy, fz = offset / max(distance, 1e-12)
    return distance, math.degrees(math.atan2(-fx, fy)), math.degrees(math.asin(max(-1.0, min(1.0, fz))))


def chase_eye(robot: Sequence[float], goal: Sequence[float], back: float, up: float) -> np.ndarray:
    """Where a camera behind and above ``robot`` looking towards ``goal`` sits: ``back`` metres back from the robot
    along the horizontal direction away from the goal and ``up`` metres above it (when the goal is straight above or
    below the robot, back along -x)."""
    robot = np.asarray(robot, dtype=float)
    away = robot[:2] - np.asarray(goal, dtype=float)[:2]
    norm = float(np.hypot(*away))
    direction = away / norm if norm > 1e-6 else np.array([-1.0, 0.0])
    return robot + np.array([back * direction[0], back * direction[1], up])


def between(robot: Sequence[float], goal: Sequence[float], eye: Sequence[float], goal_weight: float) -> np.ndarray:
    """A point to aim a camera at ``eye`` so that ``robot`` and ``goal`` both sit near the centre: along the
    direction between the unit directions to the two, ``goal_weight`` in [0, 1] of the way to the goal's (0: the
    robot in the centre)."""
    eye = np.asarray(eye, dtype=float)
    to_robot, to_goal = np.asarray(robot, dtype=float) - eye, np.asarray(goal, dtype=float) - eye
    reach = float(np.linalg.norm(to_robot))
    aim = (1.0 - goal_weight) * _unit(to_robot) + goal_weight * _unit(to_goal)
    if np.linalg.norm(aim) < 1e-9:
        return eye + to_robot
    return eye + reach * _unit(aim)


def pull_in(anchor: Sequence[float], eye: Sequence[float], free_fraction: float, margin: float,
            shortest: float) -> np.ndarray:
    """A spring arm: ``eye`` moved towards ``anchor`` so that the segment between them stays clear of what lies
    ``free_fraction`` of the way out (a ray's hit fraction, 1: nothing), ``margin`` metres short of the hit, and no
    nearer than ``shortest`` metres."""
    anchor, eye = np.asarray(anchor, dtype=float), np.asarray(eye, dtype=float)
    arm = eye - anchor
    length = float(np.linalg.norm(arm))
    if free_fraction >= 1.0 or length <= shortest:
        return eye
    reach = max(shortest, free_fraction * length - margin)
    return anchor + arm * (min(reach, length) / length)


def fitting_distance(points: np.ndarray | Sequence[Sequence[float]], target: Sequence[float],
                     direction: Sequence[float], shortest: float, longest: float, width: int, height: int,
                     inset: float, fov_deg: float = FOV_DEG) -> float:
    """The least distance in [``shortest``, ``longest``] metres from ``target`` along the unit vector ``direction``
    at which a camera aimed at ``target`` shows every one of ``points`` (n, 3) at least ``inset`` of the frame's
    half-size inside its edges (found by bisection to a millimetre, so the distance changes smoothly as the points
    move); ``longest`` when none does."""
    target, direction = np.asarray(target, dtype=float), np.asarray(direction, dtype=float)
    points = np.asarray(points, dtype=float)

    def fits(distance: float) -> bool:
        view = CameraView(tuple(target + distance * direction), tuple(target), width, height, fov_deg)
        ndc, in_front = view.normalised(points)  # 0 at the centre, +-1 on the frame's edges
        return bool(in_front.all() and np.abs(ndc).max() <= 1.0 - inset)

    if fits(shortest) or not fits(longest):
        return float(shortest if fits(shortest) else longest)
    near, far = shortest, longest
    while far - near > 1e-3:
        middle = 0.5 * (near + far)
        near, far = (near, middle) if fits(middle) else (middle, far)
    return float(far)


def _unit(v: np.ndarray) -> np.ndarray:
    norm = float(np.linalg.norm(v))
    return v / norm if norm > 1e-12 else v
