"""The reduced drive model (clutter_gym.dynamics.drive_model) against closed forms: the unicycle's arc at constant
side speeds, the ramp of an acceleration limit, and the first-order lag's geometric approach."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.dynamics.drive_model import LEFT, RIGHT, STATE_SIZE, YAW, DriveParams, X, Y, drive_ticks

DT = 1.0 / 120.0


@pytest.mark.parametrize(("left", "right"), [(0.3, 0.5), (-0.2, 0.4), (0.4, 0.4), (0.25, -0.25)])
def test_constant_side_speeds_drive_the_unicycle_arc(left, right):
    """Sides already at their commands: after 5 s the base is where the unicycle's arc puts it, x = R sin(wt),
    y = R (1 - cos(wt)), heading wt, to 1e-9 m (each tick's step is the exact arc; only rounding remains)."""
    params = DriveParams(acceleration=100.0, time_constant=0.0, scrub=0.0, track=0.3, wheel_track=0.3)
    state = np.array([0.0, 0.0, 0.0, left, right, 0.0, 0.0])
    ticks = 600
    drive_ticks(state, left, right, params.as_array(), DT, ticks)
    t = ticks * DT
    v, w = 0.5 * (left + right), (right - left) / 0.3
    if w == 0.0:
        expected = (v * t, 0.0)
    else:
        expected = (v / w * math.sin(w * t), v / w * (1.0 - math.cos(w * t)))
    assert state[X] == pytest.approx(expected[0], abs=1e-9)
    assert state[Y] == pytest.approx(expected[1], abs=1e-9)
    assert math.remainder(state[YAW] - w * t, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_an_acceleration_limit_ramps_the_speed_and_the_distance_is_the_ramps():
    """From rest, no lag, a 2 m/s^2 limit towards 0.5 m/s on both sides: the speed is min(a t, 0.5) after every tick
    (exact), and the distance after 1 s is the ramp's 0.5 a T^2 plus the cruise, within one tick's travel."""
    a = 2.0
    params = DriveParams(acceleration=a, time_constant=0.0, scrub=0.0, track=0.3, wheel_track=0.3).as_array()
    state = np.zeros(STATE_SIZE)
    for tick in range(1, 121):
        drive_ticks(state, 0.5, 0.5, params, DT, 1)
        assert state[LEFT] == pytest.approx(min(a * tick * DT, 0.5), abs=1e-12)
        assert state[RIGHT] == state[LEFT]
    ramp = 0.5 / a
    assert state[X] == pytest.approx(0.5 * a * ramp**2 + 0.5 * (1.0 - ramp), abs=0.5 * DT)


def test_a_time_constant_approaches_geometrically():
    """No acceleration limit, a 0.1 s lag: after n ticks the speed is 0.4 (1 - (1 - dt/tau)^n) exactly, and within
    dt / tau of the continuous 0.4 (1 - exp(-t / tau))."""
    tau = 0.1
    params = DriveParams(acceleration=1e6, time_constant=tau, scrub=0.0, track=0.3, wheel_track=0.3).as_array()
    state = np.zeros(STATE_SIZE)
    drive_ticks(state, 0.4, 0.4, params, DT, 30)
    assert state[LEFT] == pytest.approx(0.4 * (1.0 - (1.0 - DT / tau) ** 30), abs=1e-12)
    assert state[LEFT] == pytest.approx(0.4 * (1.0 - math.exp(-30 * DT / tau)), abs=0.4 * DT / tau)


def test_scrub_takes_its_share_of_the_forward_speed_in_a_turn():
    """With scrub 0.05 s/rad, turning at 2 rad/s the base moves at 0.9 of its sides' mean speed."""
    params = DriveParams(acceleration=100.0, time_constant=0.0, scrub=0.05, track=0.3, wheel_track=0.3)
    left, right = params.sides(0.4, 2.0)
    v, w = params.body(left, right)
    assert (v, w) == pytest.approx((0.36, 2.0))
