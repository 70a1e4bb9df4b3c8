"""A multirotor's inner loop: body-rate PI control and the mixer from thrust and torques to rotor thrusts.

It runs once per physics tick, on 3-vectors and a handful of rotors, so it works on Python floats: numpy's cost per
call is many times that of the arithmetic at these sizes. Matrices are turned into tuples of rows once, when a
controller or mixer is made. The rate loop turns a body-rate setpoint into a torque,
``tau = J (kp * e + ki * integral(e)) + w x J w`` with ``e = w_ref - w`` in the body frame: gains are in 1/s and
1/s^2 and scaled by the inertia ``J``, as PX4 and Betaflight scale theirs by the airframe, so the same gains give
the same closed loop on any inertia. The gyroscopic term ``w x J w`` cancels the coupling between the axes.

The mixer inverts the allocation (collective thrust and three torques from the rotor thrusts; with more than four
rotors, its pseudo-inverse) and, when the rotors cannot give all of it, gives up what matters least first: yaw
torque, then collective thrust, then roll and pitch torque scaled down together (their direction kept). The
attitude then stays controllable when the thrust saturates, as in PX4's mixer.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from clutter_gym.util.transforms import Vector3, times


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

    Attributes:
        inertia: ``inertia`` as 9 floats, row by row.
        integral: the integrated rate error, rad, per axis.
    """

    def __init__(self, inertia: np.ndarray, gains: RateGains, dt: float) -> None:
        self.inertia = tuple(np.asarray(inertia, dtype=float).ravel().tolist())
        self.kp = tuple(float(k) for k in gains.kp)
        self.ki = tuple(float(k) for k in gains.ki)
        self.dt = dt
        self.limit = gains.integral_limit
        self.integral: Vector3 = (0.0, 0.0, 0.0)

    def reset(self) -> None:
        """Empty the integrator (a new episode)."""
        self.integral = (0.0, 0.0, 0.0)

    def torque(self, rate_ref: Sequence[float], rate: Sequence[float]) -> Vector3:
        """Body torque (N m, body frame) for the setpoint ``rate_ref`` at the measured body rate ``rate`` (rad/s)."""
        dt, limit = self.dt, self.limit
        p, q, r = rate
        ref_p, ref_q, ref_r = rate_ref
        ep, eq, er = ref_p - p, ref_q - q, ref_r - r
        ip, iq, ir = self.integral
        ip, iq, ir = _clip(ip + ep * dt, limit), _clip(iq + eq * dt, limit), _clip(ir + er * dt, limit)
        self.integral = ip, iq, ir
        (kp_p, kp_q, kp_r), (ki_p, ki_q, ki_r) = self.kp, self.ki
        # the angular acceleration the gains ask for, then J times it, plus rate x (J rate)
        tp, tq, tr = times(self.inertia, (kp_p * ep + ki_p * ip, kp_q * eq + ki_q * iq, kp_r * er + ki_r * ir))
        hp, hq, hr = times(self.inertia, rate)
        return tp + (q * hr - r * hq), tq + (r * hp - p * hr), tr + (p * hq - q * hp)


def _clip(x: float, limit: float) -> float:
    """``x`` within [-limit, limit]."""
    return -limit if x < -limit else limit if x > limit else x


def allocation(positions: np.ndarray, spin: np.ndarray, torque_ratio: float) -> np.ndarray:
    """The (4, n) matrix from rotor thrusts (N) to (collective thrust N, roll, pitch, yaw torque N m), body frame.

    Args:
        positions: (n, 2) rotor hub positions (x, y) in the body frame relative to the centre of mass, metres.
        spin: (n,) +1 for counter-clockwise rotors seen from above, -1 for clockwise.
        torque_ratio: km / kf, metres: yaw torque per newton of a rotor's thrust.
    """
    x, y = positions[:, 0], positions[:, 1]
    return np.vstack([np.ones_like(x), y, -x, -torque_ratio * spin])


def mixing_matrix(allocation_matrix: np.ndarray) -> np.ndarray:
    """The (n, 4) matrix from (collective thrust, roll, pitch, yaw torque) to rotor thrusts: the inverse of a (4, 4)
    allocation, else its pseudo-inverse (of all the rotor thrusts that meet a demand, the one with the least sum of
    squares). Its first column is each rotor's share of the collective thrust.

    The pseudo-inverse of a square allocation is its inverse too, to rounding: four rotors take the exact inverse,
    which the seeded trajectories were recorded with.
    """
    if allocation_matrix.shape == (4, 4):
        return np.linalg.inv(allocation_matrix)
    return np.linalg.pinv(allocation_matrix)


class Mixer:
    """Rotor thrusts for a collective thrust and body torques, within the rotors' thrust range.

    Args:
        allocation_matrix: (4, n) from :func:`allocation`, of rank 4, and every rotor's share of the collective thrust
            positive (``robots/multirotor_model.py`` checks a spec's layout).
        min_thrust: lowest thrust of one rotor, N.
        max_thrust: highest thrust of one rotor, N.

    Attributes:
        shares: each rotor's share of the collective thrust (they sum to 1).
        torque_rows: per rotor, its thrust (N) per roll, pitch and yaw torque (N m).
    """

    def __init__(self, allocation_matrix: np.ndarray, min_thrust: float, max_thrust: float) -> None:
        inverse = mixing_matrix(allocation_matrix)
        self.shares = tuple(inverse[:, 0].tolist())
        self.torque_rows = tuple(map(tuple, inverse[:, 1:].tolist()))  # per rotor: N per roll, pitch, yaw N m
        self.min_thrust = min_thrust
        self.max_thrust = max_thrust

    def mix(self, thrust: float, torque: Sequence[float]) -> np.ndarray:
        """:meth:`thrusts` as an array."""
        return np.array(self.thrusts(float(thrust), [float(t) for t in torque]))

    def thrusts(self, thrust: float, torque: Sequence[float]) -> list[float]:
        """Rotor thrusts (N) for ``thrust`` (N, collective) and ``torque`` (N m, body frame).

        Within the range every demand is met exactly. Outside it: roll and pitch are scaled down (in ratio) until
        their spread fits the range; yaw is then scaled down until it fits beside them; last the collective is
        moved as little as needed to bring every rotor into the range.
        """
        lo, hi = self.min_thrust, self.max_thrust
        span = hi - lo
        tx, ty, tz = torque
        differential = [a * tx + b * ty + c * tz for a, b, c in self.torque_rows]  # roll and pitch, + yaw
        if max(differential) - min(differential) > span:
            rp = [a * tx + b * ty for a, b, _ in self.torque_rows]
            yaw = [c * tz for _, _, c in self.torque_rows]
            rp_spread = max(rp) - min(rp)
            if rp_spread > span:
                scale = span / rp_spread
                differential = [r * scale for r in rp]
            else:
                # the spread is the largest pairwise difference (rp_i - rp_j) + k (yaw_i - yaw_j): keep the
                # largest yaw scale k in [0, 1] for which every pair fits the span
                k = min((span - (rp_i - rp_j)) / (yaw_i - yaw_j)
                        for rp_i, yaw_i in zip(rp, yaw) for rp_j, yaw_j in zip(rp, yaw) if yaw_i > yaw_j)
                k = max(0.0, k)
                differential = [r + y * k for r, y in zip(rp, yaw)]
        shares = self.shares
        thrusts = [thrust * c + d for c, d in zip(shares, differential)]
        # the collective moves by the least that brings every rotor into range, each rotor by its share of it (which
        # changes no torque); with equal shares the differential part fits the span by construction, with unequal
        # ones a rotor the move pushes past the other end is held there
        if min(thrusts) < lo:
            shift = max((lo - f) / c for f, c in zip(thrusts, shares))
            thrusts = [min(f + shift * c, hi) for f, c in zip(thrusts, shares)]  # min: rounding
        elif max(thrusts) > hi:
            shift = max((f - hi) / c for f, c in zip(thrusts, shares))
            thrusts = [max(f - shift * c, lo) for f, c in zip(thrusts, shares)]
        return thrusts
