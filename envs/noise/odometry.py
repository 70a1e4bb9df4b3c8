"""Wheel-encoder odometry noise: encoder quantisation and the two systematic errors of a differential drive's
dead reckoning, an error in each wheel's radius and one in the effective track width.

Pure functions on plain numbers, no simulator. Borenstein and Feng's UMBmark (O7, a row of
``SENSOR_NOISE.references``) names unequal wheel diameters and an uncertain wheelbase as the dominant systematic
errors: the odometry divides encoder counts by the radii and the track it believes in, which differ from the robot's.
Here they are drawn once per episode, a scale per wheel side ``1 + N(0, radius_sigma_frac)`` and for the track
``1 + N(0, track_sigma_frac)``. Wheel slip against the floor needs no parameter: the encoders read the simulated
wheels' rotation, and the physics slips them. Encoders count whole ticks (``ticks_per_rev`` a revolution; 0 =
exact). ``SENSOR_NOISE`` holds the values of each named profile with their sources, the model in words and the source
rows, which docs/sensors.md shows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clutter_gym.noise.params import NoiseParams, param
from clutter_gym.noise.profiles import Reference, SensorNoiseSection


@dataclass(frozen=True)
class OdometryNoise(NoiseParams):
    """Attributes:
    ticks_per_rev: encoder ticks per wheel revolution; 0 counts the wheel's angle exactly.
    radius_sigma_frac: 1-sigma relative error of the radius the odometry believes each wheel side has.
    track_sigma_frac: 1-sigma relative error of the track width it believes in.
    """

    section = "odometry"
    ticks_per_rev: int = param(0, 0, 1_000_000, "ticks", "encoder resolution (0 = exact)", integer=True)
    radius_sigma_frac: float = param(0.0, 0.0, 0.1, "", "per-episode wheel radius error, each side")
    track_sigma_frac: float = param(0.0, 0.0, 0.2, "", "per-episode track width error")


def start_odometry_episode(rng: np.random.Generator, params: OdometryNoise) -> tuple[float, float, float]:
    """This episode's (left radius, right radius, track) scales the odometry believes in; nothing is drawn for a
    parameter that is 0."""
    left = right = track = 1.0
    if params.radius_sigma_frac:
        left, right = 1.0 + params.radius_sigma_frac * rng.standard_normal(2)
    if params.track_sigma_frac:
        track = 1.0 + params.track_sigma_frac * float(rng.standard_normal())
    return float(left), float(right), float(track)


def encoder_angle(angle: float, ticks_per_rev: int) -> float:
    """A wheel angle (rad) as an encoder counts it: whole ticks, rounded towards minus infinity."""
    if not ticks_per_rev:
        return angle
    tick = 2.0 * math.pi / ticks_per_rev
    return math.floor(angle / tick) * tick


SENSOR_NOISE = SensorNoiseSection(
    name="odometry",
    params=OdometryNoise,
    timed=True,
    model="Per episode, scales of the radius each wheel side is believed to have, `1 + N(0, radius_sigma_frac)`, "
          "and of the track, `1 + N(0, track_sigma_frac)` (UMBmark's E_d and E_b, O7); encoder counts floored to "
          "whole ticks (`ticks_per_rev`); wheel slip is the physics' own (the encoders read the simulated wheels).",
    references={
        "O4": Reference("TurtleBot3 wheel encoders (DYNAMIXEL XL430-W250 / XM430-W210)",
                        "contactless absolute encoder, 12 bit over 360° → 4096 ticks per wheel revolution",
                        "emanual.robotis.com/docs/en/platform/turtlebot3/appendix_dynamixel (specifications table, "
                        "\"Position Sensor\")"),
        "O5": Reference("Duckietown Duckiebot wheel encoders", "135 ticks per wheel revolution",
                        "`duckietown/lx-kinematics-odometry:notebooks/03-Odometry/odometry.ipynb` (\"N_tot = 135 for "
                        "the wheel encoders we will be using\")"),
        "O6": Reference("SparkFun RedBot wheel encoders", "192 ticks per wheel revolution",
                        "`MrYsLab/rb4s` wiki, \"Wheel Encoder Blocks\""),
        "O7": Reference("Systematic odometry errors of a differential drive",
                        "unequal wheel diameters (E_d) and an uncertain effective wheelbase (E_b) dominate; UMBmark "
                        "measures both; sizes depend on the robot and are not given here",
                        "J. Borenstein, L. Feng, \"Measurement and correction of systematic odometry errors in mobile "
                        "robots\", IEEE Trans. Robotics and Automation 12(6), 1996; summarised in Martinelli et al. "
                        "(EPFL), \"Simultaneous localization and odometry self calibration for mobile robot\", and "
                        "solderspot.wordpress.com/2014/05/08/navbot-error-correction-using-umbmark"),
    },
    profiles={
        "nominal": {
            "ticks_per_rev": (4096, "O4 TurtleBot3 DYNAMIXEL 12-bit absolute encoder"),
            "radius_sigma_frac": (0.002, "UNSOURCED: calibrated tyres; O7 names the error, not its size"),
            "track_sigma_frac": (0.01, "UNSOURCED: a track measured to a few mm; O7 names the error"),
        },
        "low-cost": {
            "ticks_per_rev": (192, "O6 SparkFun RedBot wheel encoder"),
            "radius_sigma_frac": (0.005, "UNSOURCED: uncalibrated hobby wheels; O7"),
            "track_sigma_frac": (0.02, "UNSOURCED: wide tyres, an uncertain contact line; O7"),
        },
        "harsh": {
            "ticks_per_rev": (135, "O5 Duckietown wheel encoder"),
            "radius_sigma_frac": (0.01, "UNSOURCED: soft tyres under load; O7"),
            "track_sigma_frac": (0.05, "UNSOURCED: skid on carpet moves the contact line; O7"),
        },
    },
)
