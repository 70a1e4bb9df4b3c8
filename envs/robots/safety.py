"""A collision monitor for the differential-drive base: slows the forward command when the LIDAR sees the arc
the robot is about to drive crossing an obstacle.

It plays the part of the safety layer a real mobile base runs between its planner and its motors (a "slowdown
zone" collision monitor, or the admissible-velocity check of the dynamic window approach): it predicts the
footprint's path under the command for a short horizon and lowers the linear speed until that path keeps its
distance from every LIDAR return. The yaw rate is left alone: the footprint is a circle about the base origin,
so turning in place never brings it closer to anything.

It reads the scan the policy reads (noisy, delayed and held under a noise profile), so it is only as good as
the sensor, as on a robot.

A monitor alone can pin a robot: a controller that keeps commanding the same blocked motion stands still for
good. With ``recovery > 0`` the monitor also runs the simplest recovery behaviour of a navigation stack (a
"spin"): once the whole forward command has been held back for ``recovery`` seconds in a row, it takes over and
turns the base in place, away from the nearest return, by :data:`RECOVERY_TURN` at full yaw rate, then hands
control back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Forward-speed fractions tried, largest first; the last (0: turn in place) never moves the footprint.
SPEED_SCALES = (1.0, 0.75, 0.5, 0.25, 0.0)
#: Footprint positions checked along the predicted arc.
ARC_SAMPLES = 8
#: Radians the recovery spin turns the base, at full yaw rate.
RECOVERY_TURN = 0.8


@dataclass(frozen=True)
class SafetyConfig:
    """How far ahead the monitor looks and how much room it keeps.

    Attributes:
        horizon: seconds of driving predicted, [0, 2]; 0 turns the monitor off.
        margin: clearance in metres the predicted footprint must keep from every LIDAR return, [0, 0.5]. When
            the robot is already closer than that, the arc must not bring it closer than it is.
        recovery: seconds the whole forward command may stay held back before the recovery spin, [0, 10];
            0: never (the monitor holds the robot for as long as the command stays blocked).
    """

    horizon: float = 0.3
    margin: float = 0.02
    recovery: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.horizon) and 0.0 <= self.horizon <= 2.0):
            raise ValueError(f"safety_horizon must be in [0, 2] seconds (0: off), got {self.horizon!r}")
        if not (math.isfinite(self.margin) and 0.0 <= self.margin <= 0.5):
            raise ValueError(f"safety_margin must be in [0, 0.5] metres, got {self.margin!r}")
        if not (math.isfinite(self.recovery) and 0.0 <= self.recovery <= 10.0):
            raise ValueError(f"safety_recovery must be in [0, 10] seconds (0: never), got {self.recovery!r}")
        if self.recovery > 0.0 and self.horizon == 0.0:
            raise ValueError(f"safety_recovery > 0 needs the collision monitor on (safety_horizon in (0, 2] "
                             f"seconds), got safety_horizon 0 and safety_recovery {self.recovery}")


class SafetyFilter:
    """Scales the linear part of a normalised (linear, angular) command by the largest of :data:`SPEED_SCALES`
    whose predicted arc is clear, and runs the recovery spin when the robot stays pinned.

    Stateful for the recovery: call :meth:`reset` at the start of every episode.

    Args:
        config: horizon, margin and recovery.
        footprint_radius: radius of the robot's footprint circle about the base origin, metres.
        max_linear_speed, max_angular_speed: what a command of 1 means, m/s and rad/s.
        beam_angles: LIDAR beam azimuths, radians, in the base frame (a 2D scanner mounted level).
        mount_xy: the scan origin in the base frame, metres.
        max_range: a range at or beyond it is no return.
        control_dt: seconds between two commands.

    Attributes:
        sensor: the name of the sensor whose readings (ranges, metres, one per beam) :meth:`filter` takes; the env
            hands it that sensor's latest delivered reading, with the agent's latency and sample-and-hold.
    """

    sensor = "lidar"

    def __init__(
        self,
        config: SafetyConfig,
        footprint_radius: float,
        max_linear_speed: float,
        max_angular_speed: float,
        beam_angles: np.ndarray,
        mount_xy: tuple[float, float],
        max_range: float,
        control_dt: float,
    ) -> None:
        self.config = config
        self.reach = footprint_radius + config.margin
        self._speeds = (max_linear_speed, max_angular_speed)
        self._cos, self._sin = np.cos(beam_angles), np.sin(beam_angles)
        self._mount = mount_xy
        self._max_range = max_range
        self._times = config.horizon * np.arange(1, ARC_SAMPLES + 1) / ARC_SAMPLES
        # recovery: steps held before the spin (0: never), and the spin's length in steps
        self._patience = max(1, round(config.recovery / control_dt)) if config.recovery > 0.0 else 0
        self._spin_steps = max(1, math.ceil(RECOVERY_TURN / (max_angular_speed * control_dt) - 1e-9))
        self.reset()

    def reset(self) -> None:
        """Forget the previous episode: nothing held, no spin under way."""
        self._held = 0
        self._spin_left = 0
        self._spin_direction = 0.0
        self.recovering = False  # whether the last filter() call was a recovery spin (the command ignored)

    def points(self, ranges: np.ndarray) -> np.ndarray:
        """LIDAR returns as (n, 2) points in the base frame; beams without a return (>= max_range, inf) dropped."""
        hit = np.isfinite(ranges) & (ranges < self._max_range)
        r = ranges[hit]
        return np.stack([self._mount[0] + r * self._cos[hit], self._mount[1] + r * self._sin[hit]], axis=1)

    def scale(self, command: np.ndarray, ranges: np.ndarray) -> float:
        """The fraction of ``command``'s linear speed that is safe to drive, given the latest scan ``ranges``."""
        if command[0] == 0.0:
            return 1.0
        pts = self.points(ranges)
        if len(pts) == 0:
            return 1.0
        now = float(np.sqrt(np.min(pts[:, 0] ** 2 + pts[:, 1] ** 2)))
        keep = min(self.reach, now)  # never demand more room than there is: only forbid getting closer
        w = float(command[1]) * self._speeds[1]
        for s in SPEED_SCALES[:-1]:
            v = s * float(command[0]) * self._speeds[0]
            path = arc(v, w, self._times)
            d2 = (pts[None, :, 0] - path[:, None, 0]) ** 2 + (pts[None, :, 1] - path[:, None, 1]) ** 2
            if math.sqrt(float(d2.min())) >= keep - 1e-9:
                return s
        return SPEED_SCALES[-1]

    def filter(self, command: np.ndarray, ranges: np.ndarray) -> tuple[np.ndarray, float]:
        """The command to drive and the scale applied to ``command``'s linear part: ``command`` with its linear
        part scaled, or, during a recovery spin, a turn in place (scale 0)."""
        self.recovering = self._spin_left > 0
        if self.recovering:
            self._spin_left -= 1
            return np.array([0.0, self._spin_direction], dtype=command.dtype), 0.0
        s = self.scale(command, ranges)
        self._held = self._held + 1 if s == 0.0 else 0
        if self._patience and self._held >= self._patience:
            self._start_spin(ranges)
        if s == 1.0:
            return command, s
        out = command.copy()
        out[0] *= s
        return out, s

    def _start_spin(self, ranges: np.ndarray) -> None:
        """Queue a spin away from the nearest return, starting with the next command."""
        self._held = 0
        pts = self.points(ranges)
        if len(pts):  # the scan that held the robot had returns; a robot held back always has one
            nearest = pts[np.argmin(pts[:, 0] ** 2 + pts[:, 1] ** 2)]
            self._spin_direction = -1.0 if nearest[1] > 0.0 else 1.0  # obstacle to the left: turn right
            self._spin_left = self._spin_steps


def arc(v: float, w: float, times: np.ndarray) -> np.ndarray:
    """Base-origin positions (len(times), 2) of a unicycle starting at the origin heading +x, driving at ``v``
    m/s and ``w`` rad/s for each of ``times`` seconds."""
    if abs(w) < 1e-6:
        return np.stack([v * times, np.zeros_like(times)], axis=1)
    rho = v / w
    return np.stack([rho * np.sin(w * times), rho * (1.0 - np.cos(w * times))], axis=1)
