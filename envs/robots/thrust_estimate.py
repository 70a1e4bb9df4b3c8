"""The flight controller's estimate of how much thrust the airframe really gets: the ratio of the specific force
the rotors give along the body's z axis to the one the nominal model predicts from the rotor speeds.

On the nominal airframe it reads 1; on one that is 20% heavier, or whose motors are 20% weaker, it reads about
0.83 or 0.8 (``motor strength / mass scale``), which a controller that knows only the datasheet cannot tell
apart from a slow climb. Flight stacks estimate the same quantity as a hover thrust (PX4's hover thrust
estimator). Each physics tick gives one sample, the measured acceleration along body z plus gravity's share
over the nominal thrust per nominal mass; a first-order filter with time constant ``time_constant`` smooths the
samples, so the estimate is an integrator state a memoryless policy can read.

All on Python floats: it runs every physics tick, on 3-vectors.
"""

from __future__ import annotations

import math

#: The estimate's bounds: samples outside them (a contact, a thrust near zero) are clipped.
RATIO_BOUNDS = (0.25, 4.0)
#: Samples are skipped while the nominal thrust is below this share of the weight: the ratio of two small
#: numbers is mostly noise.
MIN_THRUST_SHARE = 0.1


class ThrustRatioEstimator:
    """``ratio``: the filtered estimate, 1.0 after :meth:`reset`; ``velocity``: the last tick's velocity (m/s, world),
    None after it.

    Args:
        nominal_mass: kg, the model's mass.
        gravity: m/s^2.
        dt: seconds between two :meth:`update` calls (a physics tick).
        time_constant: seconds, of the first-order filter (> 0).
    """

    def __init__(self, nominal_mass: float, gravity: float, dt: float, time_constant: float) -> None:
        if not (math.isfinite(time_constant) and time_constant > 0.0):
            raise ValueError(f"time_constant must be > 0 seconds, got {time_constant!r}")
        self.nominal_mass, self.gravity, self.dt = nominal_mass, gravity, dt
        self.gain = 1.0 - math.exp(-dt / time_constant)
        self._min_thrust = MIN_THRUST_SHARE * nominal_mass * gravity
        self.ratio = 1.0
        self.velocity: tuple[float, float, float] | None = None

    def reset(self) -> None:
        """Back to the nominal model (1.0), with no velocity to difference against."""
        self.ratio = 1.0
        self.velocity = None

    def update(self, body_z: tuple[float, float, float], velocity: tuple[float, float, float],
               nominal_thrust: float) -> None:
        """One tick: ``velocity`` (m/s, world) now; ``nominal_thrust`` (N) the model's thrust over the tick that
        ended here, along ``body_z`` (the body's z axis in the world, a unit vector)."""
        previous, self.velocity = self.velocity, velocity
        if previous is None or nominal_thrust < self._min_thrust:
            return
        inv_dt = 1.0 / self.dt
        fx = (velocity[0] - previous[0]) * inv_dt
        fy = (velocity[1] - previous[1]) * inv_dt
        fz = (velocity[2] - previous[2]) * inv_dt + self.gravity
        sample = (fx * body_z[0] + fy * body_z[1] + fz * body_z[2]) * self.nominal_mass / nominal_thrust
        lo, hi = RATIO_BOUNDS
        sample = lo if sample < lo else hi if sample > hi else sample
        self.ratio += self.gain * (sample - self.ratio)
