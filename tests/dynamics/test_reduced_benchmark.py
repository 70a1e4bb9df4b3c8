"""benchmarks/dynamics/reduced_error.py runs as its docs say, on a small budget: the divergence grows with time from
millimetres, and the closed loop runs nearly every step of a scripted drive under the reduced model."""

from __future__ import annotations

from benchmarks.dynamics.reduced_error import MARKS, closed_loop, divergence


def test_the_divergence_is_small_after_a_second_and_reported_at_each_mark():
    gaps = divergence(drives=2)
    assert sorted(gaps) == sorted(MARKS)
    position, heading = gaps[1.0]
    assert position.max() < 0.05 and heading.max() < 0.05


def test_the_closed_loop_runs_reduced_far_from_obstacles_and_reports_its_figures():
    row = closed_loop("reduced", episodes=2, density=0.12)
    assert row["reduced"] > 0.5 and row["ms"] > 0.0
    assert set(row) == {"success", "collisions", "ms", "reduced"}
    assert closed_loop("physics", episodes=1, density=0.12)["reduced"] == 0.0
