"""The hand's pose on one family of orientations: its approach axis in the vertical plane through the target, pitched
from level (0) to pointing down (pi / 2), its fingers' opening axis level.

A pose on that family is a point and a pitch: four numbers, where a free orientation is six. The line-up paths into
a shelf (:mod:`clutter_gym.planning.line_up`) and the hand controller a student policy acts through
(``clutter_gym.training.hand_controller``) both solve for it by damped least squares on the forward kinematics,
with a numeric Jacobian. Nothing here loads a collision engine.
"""

from __future__ import annotations

import numpy as np

from clutter_gym.robots.arm_model import ArmModel
from clutter_gym.urdf.kinematics import UrdfKinematics

#: Finite-difference step of the pose Jacobian, radians.
_EPS = 1e-5
#: Metres of position error that weigh as much as a unit of axis error in the least squares: a 0.1 rad turn of the
#: hand counts as 1 cm, so that the hand reaches its point first and turns on the way.
AXIS_WEIGHT = 0.1
#: Radians from a joint limit within which a step holds the joint instead of moving it further.
LIMIT_BAND = 0.05
#: Share of the way to the rest posture the redundant motion takes in one step.
POSTURE_GAIN = 0.1


def approach_axis(target: np.ndarray) -> np.ndarray:
    """The horizontal unit vector from the arm's base towards ``target``."""
    a = np.array([target[0], target[1], 0.0])
    return a / max(float(np.linalg.norm(a)), 1e-9)


def hand_axis(target: np.ndarray, pitch: float) -> np.ndarray:
    """The hand's approach axis: :func:`approach_axis` turned ``pitch`` radians below horizontal."""
    return np.cos(pitch) * approach_axis(target) - np.sin(pitch) * np.array([0.0, 0.0, 1.0])


class HandPose:
    """Forward kinematics of an arm's hand, and damped-least-squares steps towards a pose of the family.

    Args:
        arm: the arm.
    """

    def __init__(self, arm: ArmModel) -> None:
        self.arm = arm
        self.kinematics = UrdfKinematics(arm.urdf)
        self.lower, self.upper = np.asarray(arm.lower, dtype=float), np.asarray(arm.upper, dtype=float)
        self.n_joints = len(arm.arm_joints)

    def link_frames(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Every link's frames (n, 4, 4) at arm configurations ``q`` (n, n_joints), fingers (if any) at their
        opening."""
        q = np.atleast_2d(q)
        fingers = np.full((len(q), len(self.arm.finger_joints)), self.arm.finger_opening)
        return self.kinematics.forward(np.concatenate([q, fingers], axis=1))

    def frames(self, q: np.ndarray) -> np.ndarray:
        """The hand's frames (n, 4, 4) at arm configurations ``q`` (n, n_joints)."""
        return self.link_frames(q)[self.arm.ee_link]

    def residual(self, q: np.ndarray, point: np.ndarray, axis: np.ndarray) -> np.ndarray:
        """(n, 7): the hand's offset from ``point``, its approach (z) axis minus ``axis``, and the vertical
        component of its fingers' opening (y) axis, at configurations ``q`` (n, n_joints)."""
        frame = self.frames(q)
        return np.concatenate([frame[:, :3, 3] - point, frame[:, :3, 2] - axis, frame[:, 2:3, 1]], axis=1)

    def step(self, q: np.ndarray, point: np.ndarray, axis: np.ndarray, damping: float = 0.05,
             weight: float = AXIS_WEIGHT, rest: np.ndarray | None = None, relative: bool = False) -> np.ndarray:
        """One damped-least-squares change (n, n_joints) of configurations ``q`` (n, n_joints) towards the pose,
        the axis rows weighted by ``weight``; with ``relative``, ``point`` is the hand's displacement from where it
        is at ``q`` (read from the same forward-kinematics pass). A joint the change would take within
        :data:`LIMIT_BAND` of a limit is held and the rest solved again; with ``rest`` (n_joints,), the redundant
        motion also turns the joints towards it (:data:`POSTURE_GAIN`), in the Jacobian's null space."""
        q = np.atleast_2d(q)
        n, dof = q.shape
        stacked = np.concatenate([q[:, None, :], q[:, None, :] + np.eye(dof) * _EPS], axis=1).reshape(-1, dof)
        r = self.residual(stacked, np.zeros(3) if relative else point, axis).reshape(n, dof + 1, -1)
        if relative:
            r[..., :3] -= r[:, :1, :3] + point  # each row's hand position minus (where the hand is + the move)
        r[..., 3:] *= weight
        error, jac = r[:, 0], ((r[:, 1:] - r[:, :1]) / _EPS).transpose(0, 2, 1)  # (n, 7), (n, 7, dof)
        free = np.ones((n, dof))
        for _ in range(3):  # hold the joints that would cross into the band, then solve for the others
            held = jac * free[:, None, :]
            pinv = held.transpose(0, 2, 1) @ np.linalg.inv(held @ held.transpose(0, 2, 1)
                                                          + damping**2 * np.eye(jac.shape[1]))
            change = -(pinv @ error[..., None])[..., 0]
            if rest is not None:
                null = np.eye(dof) - pinv @ held
                change += (null @ (POSTURE_GAIN * (rest - q) * free)[..., None])[..., 0]
            after = q + change
            crossing = (((after < self.lower + LIMIT_BAND) & (change < 0))
                        | ((after > self.upper - LIMIT_BAND) & (change > 0)))
            if not (crossing & (free > 0)).any():
                break
            free[crossing] = 0.0
        return change * free

    def solve(self, point: np.ndarray, axis: np.ndarray, seeds: np.ndarray, iterations: int = 80,
              tolerance: float = 0.005) -> np.ndarray:
        """Configurations (n, n_joints), one per seed, within the joint limits, with the hand at ``point`` and its
        approach axis along ``axis``; NaN rows where the steps did not converge within ``tolerance`` (metres, and
        the same in units of the axes)."""
        q = np.clip(np.atleast_2d(np.asarray(seeds, dtype=float)), self.lower, self.upper)
        for _ in range(iterations):
            q = np.clip(q + np.clip(self.step(q, point, axis, weight=1.0), -0.3, 0.3), self.lower, self.upper)
        error = np.abs(self.residual(q, point, axis)).max(axis=1)
        q[error > tolerance] = np.nan
        return q
