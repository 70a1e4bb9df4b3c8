"""The speed-against-error report (``python -m benchmarks.speed_vs_error``), run as a user runs it on two sections
(conftest's ``speed_vs_error_report``): each table's Pareto front is the settings no other is both at least as fast
as and at least as accurate as (and better in one), where speed is a time (the LIDAR's scan: lower is faster) or a
rate (the aerodynamics' steps per CPU-second: higher is faster); each choice has its plot.

The report prints three significant figures, so a row is judged only where its printed figures settle it: a row
another beats on both beyond their rounding is off the front, and a row no other could match on both is on it."""

from __future__ import annotations

import math

import pytest
from helpers import report_tables

SECTIONS = {"LIDAR ray count": ("lidar-rays", False), "Aerodynamics (ClutterFly-v1)": ("aero", True)}


def printed(cell: str) -> tuple[float, float]:
    """A figure as the report prints it, and half a unit of its last printed digit."""
    value = float(cell.replace(",", ""))
    if value == 0.0:
        return 0.0, 0.0
    if abs(value) < 1:  # three significant figures
        return value, 0.5 * 10 ** (math.floor(math.log10(abs(value))) - 2)
    return value, 0.05 if "." in cell else 0.5


@pytest.fixture(scope="module")
def tables(speed_vs_error_report):
    return report_tables((speed_vs_error_report / "speed-vs-error.md").read_text(encoding="utf-8"))


@pytest.mark.parametrize("title", SECTIONS)
def test_the_front_is_the_rows_no_other_beats_on_speed_and_error(tables, title):
    _, rate = SECTIONS[title]
    header, *rows = tables[title]
    assert header[-1] == "Pareto front"
    sign = 1.0 if rate else -1.0  # faster is larger once a time is negated
    figures = []
    for cells in rows:
        (speed, speed_err), (error, error_err) = printed(cells[1]), printed(cells[2])
        figures.append(((sign * speed - speed_err, sign * speed + speed_err), (error - error_err, error + error_err)))
    decided = 0
    for i, ((fast_lo, fast_hi), (err_lo, err_hi)) in enumerate(figures):
        others = [f for j, f in enumerate(figures) if j != i]
        beaten = any(o_fast[0] >= fast_hi and o_err[1] <= err_lo and (o_fast[0] > fast_hi or o_err[1] < err_lo)
                     for o_fast, o_err in others)
        matchable = any(o_fast[1] >= fast_lo and o_err[0] <= err_hi for o_fast, o_err in others)
        if beaten:
            assert rows[i][-1] == "", rows[i]
        elif not matchable:
            assert rows[i][-1] == "yes", rows[i]
        decided += beaten or not matchable
    assert decided >= len(rows) / 2, rows  # the rounding leaves most rows judged


@pytest.mark.parametrize("title", SECTIONS)
def test_every_choice_has_its_plot(speed_vs_error_report, title):
    key, _ = SECTIONS[title]
    plot = speed_vs_error_report / "speed-vs-error" / f"{key}.png"
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"(speed-vs-error/{key}.png)" in (speed_vs_error_report / "speed-vs-error.md").read_text(encoding="utf-8")
