"""benchmarks/dynamics/flight_error.py runs as its docs say, on a small budget: free flights agree to rounding, the
planner reference runs every step of an open episode under the reduced model, and the attitude gap is an angle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.dynamics.flight_error import MARKS, attitude_gap, closed_loop, divergence


def test_free_flights_agree_to_rounding_at_every_mark():
    gaps = divergence(flights=1)
    assert sorted(gaps) == sorted(MARKS)
    for position, attitude in gaps.values():
        assert position.max() < 1e-6 and attitude.max() < 1e-6


def test_the_closed_loop_runs_reduced_and_reports_its_figures():
    row = closed_loop("reduced", episodes=1, density=0.05)
    assert row["reduced"] > 0.5 and row["ms"] > 0.0 and row["success"] == 1.0
    assert set(row) == {"success", "collisions", "ms", "reduced"}
    assert closed_loop("physics", episodes=1, density=0.05)["reduced"] == 0.0


def test_the_attitude_gap_is_the_rotation_angle_whatever_the_quaternions_sign():
    a = np.array([0.0, 0.0, 0.0, 1.0])
    b = np.array([0.0, 0.0, math.sin(0.15), math.cos(0.15)])  # 0.3 rad about z
    assert attitude_gap(a, b) == pytest.approx(0.3) and attitude_gap(a, -b) == pytest.approx(0.3)
    assert attitude_gap(b, b) == 0.0


def test_the_reports_dynamics_choice_has_the_default_and_the_reduced_row():
    """benchmarks/dynamics/choices.py, as the speed-against-error report's "dynamics" section runs it (--quick)."""
    from benchmarks.dynamics.choices import fly_choice

    choice = fly_choice(quick=True)
    physics, reduced = choice.rows
    assert physics.default and physics.error == 0.0 and not reduced.default
    assert 0.0 <= reduced.error < 1e-3 and reduced.speed < physics.speed
    assert reduced.extra["reduced steps (%)"] > 50 and "same under both" in choice.why
