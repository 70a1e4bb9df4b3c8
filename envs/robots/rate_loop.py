"""A quadrotor's inner loop: body-rate PI control and the mixer from thrust and torques to rotor thrusts (numpy).

It runs once per physics tick. The rate loop turns a body-rate setpoint into a torque,
``tau = J (kp * e + ki * integral(e)) + w x J w`` with ``e = w_ref - w`` in the body frame: gains are in 1/s and
1/s^2 and scaled by the inertia ``J``, as PX4 and Betaflight scale theirs by the airframe, so the same gains give
the same closed loop on any inertia. The gyroscopic term ``w x J w`` cancels the coupling between the axes.

The mixer inverts the X-configuration allocation (collective thrust and three torques from four rotor thrusts)
and, when the rotors cannot give all of it, gives up what matters least first: yaw torque, then collective thrust,
then roll and pitch torque scaled down together (their direction kept). The attitude then stays controllable
when the thrust saturates, as in PX4's mixer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RateGains:
    """Per-axis (roll, pitch, yaw) gains of the body-rate loop.

    Attributes:
        kp: proportional gains, 1/s (angular acceleration per rate error).
        ki: integral gains, 1/s^2.
        integral_limit: bound on each axis' integrated rate error, rad.
    """

    kp: tuple[float, float, float]
    ki: tuple[float, float, float]
    integral_limit: float


class RateController:
    """PI control of the body rates with inertia-scaled gains; holds the integrator between ticks.

    Args:
        inertia: (3, 3) inertia about the centre of mass in body axes, kg m^2.
        gains: the loop's gains.
        dt: period of one update, seconds (the physics tick).
    """

    def __init__(self, inertia: np.ndarray, gains: RateGains, dt: float) -> None:
        self.inertia = np.asarray(inertia, dtype=float)
        self.kp = np.asarray(gains.kp, dtype=float)
        self.ki = np.asarray(gains.ki, dtype=float)
        self.dt = dt
        self.limit = gains.integral_limit
        self.integral = np.zeros(3)

    def reset(self) -> None:
        """Empty the integrator (a new episode)."""
        self.integral[:] = 0.0

    def torque(self, rate_ref: np.ndarray, rate: np.ndarray) -> np.ndarray:
        """Body torque (N m, body frame) for the setpoint ``rate_ref`` at the measured body rate ``rate`` (rad/s)."""
        error = rate_ref - rate
        integral = self.integral + error * self.dt
        self.integral = integral = np.minimum(np.maximum(integral, -self.limit), self.limit)
        j = self.inertia
        momentum = j @ rate
        p, q, r = rate.tolist()
        hx, hy, hz = momentum.tolist()
        gyroscopic = np.array([q * hz - r * hy, r * hx - p * hz, p * hy - q * hx])  # rate x (J rate)
        return j @ (self.kp * error + self.ki * integral) + gyroscopic


def allocation(positions: np.ndarray, spin: np.ndarray, torque_ratio: float) -> np.ndarray:
    """The (4, n) matrix from rotor thrusts (N) to (collective thrust N, roll, pitch, yaw torque N m), body frame.

    Args:
        positions: (n, 2) rotor hub positions (x, y) in the body frame relative to the centre of mass, metres.
        spin: (n,) +1 for counter-clockwise rotors seen from above, -1 for clockwise.
        torque_ratio: km / kf, metres: yaw torque per newton of a rotor's thrust.
    """
    x, y = positions[:, 0], positions[:, 1]
    return np.vstack([np.ones_like(x), y, -x, -torque_ratio * spin])


class Mixer:
    """Rotor thrusts for a collective thrust and body torques, within the rotors' thrust range.

    Args:
        allocation_matrix: (4, 4) from :func:`allocation`.
        min_thrust: lowest thrust of one rotor, N.
        max_thrust: highest thrust of one rotor, N.
    """

    def __init__(self, allocation_matrix: np.ndarray, min_thrust: float, max_thrust: float) -> None:
        inverse = np.linalg.inv(allocation_matrix)
        self._collective = inverse[:, 0]
        self._roll_pitch = inverse[:, 1:3]
        self._yaw = inverse[:, 3]
        self.min_thrust = min_thrust
        self.max_thrust = max_thrust

    def mix(self, thrust: float, torque: np.ndarray) -> np.ndarray:
        """Rotor thrusts (N) for ``thrust`` (N, collective) and ``torque`` (N m, body frame).

        Within the range every demand is met exactly. Outside it: roll and pitch are scaled down (in ratio) until
        their spread fits the range; yaw is then scaled down until it fits beside them; last the collective is
        moved as little as needed to bring every rotor into the range.
        """
        span = self.max_thrust - self.min_thrust
        rp = self._roll_pitch @ torque[:2]
        yaw = self._yaw * torque[2]
        differential = rp + yaw
        if differential.max() - differential.min() > span:
            rp_spread = rp.max() - rp.min()
            if rp_spread > span:
                differential = rp * (span / rp_spread)
            else:
                # the spread is the largest pairwise difference (rp_i - rp_j) + k (yaw_i - yaw_j): keep the
                # largest yaw scale k in [0, 1] for which every pair fits the span
                rise = yaw[:, None] - yaw[None, :]
                room = span - (rp[:, None] - rp[None, :])
                growing = rise > 0.0
                differential = rp + yaw * max(0.0, float((room[growing] / rise[growing]).min()))
        thrusts = thrust * self._collective + differential
        low, high = thrusts.min(), thrusts.max()
        # one common shift brings every rotor into range: the differential part fits the span by construction
        if low < self.min_thrust:
            thrusts = np.minimum(thrusts + (self.min_thrust - low), self.max_thrust)  # min: rounding
        elif high > self.max_thrust:
            thrusts = np.maximum(thrusts - (high - self.max_thrust), self.min_thrust)
        return thrusts
