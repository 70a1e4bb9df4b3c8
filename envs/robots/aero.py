"""Optional aerodynamic effects of a small quadrotor, as pure functions (both off unless a robot's config asks).

They run every physics tick on a 3-vector and four rotors, so they take any sequences of numbers and work on
Python floats: numpy's cost per call is many times that of the arithmetic at these sizes.

* ``"drag"``: rotor-induced drag, linear in the body-frame velocity and in the sum of the rotor speeds,
  ``F_body = -K (sum_i w_i) v_body`` with ``K = diag(k_xy, k_xy, k_z)`` (kg/rad), the model identified for the
  Crazyflie 2.0 by Foerster (2015).
* ``"ground_effect"``: the thrust gain of a rotor near the ground, Cheeseman and Bennett (1955),
  ``T_IGE / T_OGE = 1 / (1 - (R / (4 z))^2)`` for a rotor of radius ``R`` at height ``z`` above it. The formula
  diverges at ``z = R / 4``; below :data:`GROUND_EFFECT_MIN_HEIGHT` rotor radii it is held at its value there.

Coefficients and sources: docs/quadrotor.md.
"""

from __future__ import annotations

from collections.abc import Sequence

AERO_EFFECTS = ("drag", "ground_effect")
#: Height, in rotor radii, below which the ground-effect gain is held constant. Cheeseman and Bennett's image-rotor
#: derivation holds for heights of about half a radius and more; at 0.5 R the gain is 4/3.
GROUND_EFFECT_MIN_HEIGHT = 0.5


def rotor_drag(velocity_body: Sequence[float], rotor_speeds: Sequence[float], k_xy: float,
               k_z: float) -> tuple[float, float, float]:
    """Rotor-induced drag force in the body frame, N.

    Args:
        velocity_body: (3,) velocity of the centre of mass in body coordinates, m/s.
        rotor_speeds: (n,) rotor speeds, rad/s.
        k_xy: drag coefficient along body x and y, kg/rad.
        k_z: drag coefficient along body z, kg/rad.
    """
    total = sum(rotor_speeds)
    vx, vy, vz = velocity_body
    return -total * k_xy * vx, -total * k_xy * vy, -total * k_z * vz


def ground_effect_gain(heights: Sequence[float], rotor_radius: float) -> list[float]:
    """Thrust multiplier of each rotor at ``heights`` (m, its hub above the ground plane), >= 1.

    Heights below ``GROUND_EFFECT_MIN_HEIGHT * rotor_radius`` (and below the ground) take the value there.
    """
    lowest = GROUND_EFFECT_MIN_HEIGHT * rotor_radius
    ratios = [rotor_radius / (4.0 * max(z, lowest)) for z in heights]
    return [1.0 / (1.0 - r * r) for r in ratios]
