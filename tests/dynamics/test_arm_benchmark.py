"""benchmarks/dynamics/arm_error.py runs as its docs say, on a small budget: the hand's divergence is reported at each
mark, and the closed loop runs the proximity field's steps mostly under the reduced model."""

from __future__ import annotations

from benchmarks.dynamics.arm_error import MARKS, closed_loop, divergence


def test_the_hands_divergence_is_reported_at_each_mark_and_stays_within_centimetres():
    gaps = divergence(drives=1)
    assert sorted(gaps) == sorted(MARKS)
    assert max(g.max() for g in gaps.values()) < 0.03


def test_the_closed_loop_runs_reduced_and_reports_its_figures():
    row = closed_loop("proximity field", "reduced", episodes=2)
    assert row["reduced"] > 0.5 and row["ms"] > 0.0
    assert set(row) == {"success", "collisions", "ms", "reduced"}
    assert closed_loop("proximity field", "physics", episodes=1)["reduced"] == 0.0
