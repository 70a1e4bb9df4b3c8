"""The reduced model of a wheeled base on a flat floor: each side's ground speed follows the unicycle model's wheel
speed through a first-order lag under an acceleration limit, and the base moves as a unicycle on the sides' speeds
that loses a share of its forward speed while it turns (the wheels' scrub). Integrated per physics tick in compiled
code.

The four numbers of :class:`DriveParams` are fitted to the full-physics robot by
:func:`clutter_gym.dynamics.drive_fit.fit_drive`; docs/speed-vs-error.md gives the error that remains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

#: rows of a drive state: base origin x, y (m), yaw (rad), the left and right sides' ground speeds (m/s), and the
#: distances each side's wheels have rolled (m, what their encoders count)
X, Y, YAW, LEFT, RIGHT, LEFT_ROLLED, RIGHT_ROLLED = range(7)
STATE_SIZE = 7


@dataclass(frozen=True)
class DriveParams:
    """The actuator model of one base at one physics rate.

    Attributes:
        acceleration: the largest change of a side's ground speed, m/s^2 (the wheels' torque over the robot's mass,
            or the floor's grip where that is lower).
        time_constant: s, the first-order lag of a side's ground speed towards its command.
        scrub: s/rad, the share of forward speed lost per rad/s of yaw rate.
        track: m, the effective distance between the sides (a skid-steer base turns as if it were wider).
        wheel_track: m, the URDF's distance between the wheels: the wheels turn at the unicycle model's speeds for
            the base's forward speed and yaw rate over this track, as their motors are commanded.
    """

    acceleration: float
    time_constant: float
    scrub: float
    track: float
    wheel_track: float

    def as_array(self, accel_scale: float = 1.0) -> np.ndarray:
        """The numbers in :func:`drive_ticks`' order, the acceleration limit times ``accel_scale``."""
        return np.array([self.acceleration * accel_scale, self.time_constant, self.scrub, self.track,
                         self.wheel_track])

    def sides(self, speed: float, yaw_rate: float) -> tuple[float, float]:
        """The sides' ground speeds (left, right) m/s of a forward speed m/s and yaw rate rad/s."""
        half = 0.5 * self.track * yaw_rate
        return speed - half, speed + half

    def body(self, left: float, right: float) -> tuple[float, float]:
        """(forward speed m/s, yaw rate rad/s) of the sides' ground speeds."""
        w = (right - left) / self.track
        return 0.5 * (left + right) * max(0.0, 1.0 - self.scrub * abs(w)), w


@numba.njit(cache=True)
def drive_ticks(state: np.ndarray, left: float, right: float, params: np.ndarray, dt: float, ticks: int) -> None:
    """Advance ``state`` (rows :data:`X` ... :data:`RIGHT_ROLLED`) in place by ``ticks`` ticks of ``dt`` seconds
    towards the sides' ground-speed commands ``left`` and ``right`` (m/s). Each tick moves the base along the arc of
    its speeds (the exact unicycle step for speeds held over the tick)."""
    acceleration, time_constant, scrub, track, wheel_track = params[0], params[1], params[2], params[3], params[4]
    most = acceleration * dt
    share = min(1.0, dt / time_constant) if time_constant > 0.0 else 1.0
    x, y, yaw, u_left, u_right = state[0], state[1], state[2], state[3], state[4]
    rolled_left, rolled_right = state[5], state[6]
    for _ in range(ticks):
        u_left += min(max((left - u_left) * share, -most), most)
        u_right += min(max((right - u_right) * share, -most), most)
        w = (u_right - u_left) / track
        mean = 0.5 * (u_left + u_right)
        rolled_left += (mean - 0.5 * wheel_track * w) * dt
        rolled_right += (mean + 0.5 * wheel_track * w) * dt
        v = mean * max(0.0, 1.0 - scrub * abs(w))
        turn = w * dt
        if abs(turn) < 1e-9:
            x += v * dt * math.cos(yaw)
            y += v * dt * math.sin(yaw)
        else:
            radius = v / w
            x += radius * (math.sin(yaw + turn) - math.sin(yaw))
            y -= radius * (math.cos(yaw + turn) - math.cos(yaw))
        yaw += turn
    state[0], state[1], state[2], state[3], state[4] = x, y, math.atan2(math.sin(yaw), math.cos(yaw)), u_left, u_right
    state[5], state[6] = rolled_left, rolled_right
