"""Rotor model of a quadrotor: quadratic thrust and drag torque, first-order motor lag, speed limits.

Pure functions of rotor speeds (rad/s), testable without a simulator. They take and give one Python float per
rotor (any sequence in, lists out): they run on four rotors every physics tick, where numpy's cost per call is
many times that of the arithmetic. The coefficients, their sources and the conversions from the published units
are in docs/quadrotor.md.

Conventions: a rotor's thrust acts along its axis, the body +z. ``spin`` is +1 for a rotor that turns
counter-clockwise seen from above (angular velocity along +z) and -1 for clockwise; the air's drag on the propeller
reacts on the body as a torque about +z of ``-spin * km * w^2`` (a counter-clockwise rotor yaws the body clockwise).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class RotorModel:
    """Identical rotors with quadratic thrust and torque and a first-order speed response.

    Attributes:
        thrust_coefficient: kf, thrust per squared rotor speed, N / (rad/s)^2.
        torque_coefficient: km, drag torque per squared rotor speed, N m / (rad/s)^2.
        time_constant: tau of the speed response to a speed command, seconds (0: the speed follows at once).
        min_speed: lowest rotor speed, rad/s (0: the motor may stop).
        max_speed: highest rotor speed, rad/s.
    """

    thrust_coefficient: float
    torque_coefficient: float
    time_constant: float
    min_speed: float
    max_speed: float

    def __post_init__(self) -> None:
        values = (self.thrust_coefficient, self.torque_coefficient, self.time_constant, self.min_speed, self.max_speed)
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"rotor model values must be finite, got {values}")
        if self.thrust_coefficient <= 0.0 or self.torque_coefficient < 0.0 or self.time_constant < 0.0:
            raise ValueError("thrust_coefficient must be > 0, torque_coefficient and time_constant >= 0")
        if not 0.0 <= self.min_speed < self.max_speed:
            raise ValueError(f"need 0 <= min_speed < max_speed, got {self.min_speed}, {self.max_speed}")

    @property
    def max_thrust(self) -> float:
        """Thrust of one rotor at ``max_speed``, N."""
        return self.thrust_coefficient * self.max_speed**2

    @property
    def min_thrust(self) -> float:
        """Thrust of one rotor at ``min_speed``, N."""
        return self.thrust_coefficient * self.min_speed**2

    def thrust(self, speeds: Sequence[float]) -> list[float]:
        """Thrust of each rotor, N, along its axis: ``kf * w^2``."""
        kf = self.thrust_coefficient
        return [kf * (w * w) for w in speeds]

    def yaw_torque(self, speeds: Sequence[float], spin: Sequence[float]) -> float:
        """Total drag-reaction torque on the body about its z axis, N m: ``-sum(spin * km * w^2)``."""
        return -self.torque_coefficient * sum([s * (w * w) for s, w in zip(spin, speeds)])

    def speed_for_thrust(self, thrusts: Sequence[float]) -> list[float]:
        """Rotor speeds (rad/s) that give ``thrusts`` (N, per rotor), within the speed limits."""
        kf, lo, hi = self.thrust_coefficient, self.min_speed, self.max_speed
        speeds = []
        for f in thrusts:
            w = math.sqrt((0.0 if f < 0.0 else f) / kf)
            speeds.append(lo if w < lo else hi if w > hi else w)
        return speeds

    def decay(self, dt: float) -> float:
        """exp(-dt / tau): the fraction of a speed error left after ``dt`` seconds (0 without lag)."""
        return math.exp(-dt / self.time_constant) if self.time_constant > 0.0 else 0.0

    def step(self, speeds: Sequence[float], commands: Sequence[float], decay: float) -> list[float]:
        """Rotor speeds after one period of constant, limit-clipped ``commands``: the exact solution of
        ``dw/dt = (command - w) / tau`` over the period whose :meth:`decay` is ``decay``."""
        lo, hi = self.min_speed, self.max_speed
        out = []
        for w, command in zip(speeds, commands):
            target = lo if command < lo else hi if command > hi else command
            out.append(target + (w - target) * decay)
        return out
