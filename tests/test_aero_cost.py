"""The aerodynamics section of the speed-against-error report (conftest's ``speed_vs_error_report``, a run of
``python -m benchmarks.speed_vs_error`` as a user runs it) measures something: each effect left out costs error
where it should, the reference costs none, and only ground effect changes the hover thrust."""

from __future__ import annotations

import re

import numpy as np
import pytest
from helpers import report_tables

from clutter_gym.robots.aero import ground_effect_gain
from clutter_gym.robots.quadrotor import quadrotor_model

SETTINGS = ("off", "drag", "ground_effect", "drag + ground_effect")  # aero_cost's order; the last is the reference


@pytest.fixture(scope="module")
def aero(speed_vs_error_report):
    """The section's header and its rows by setting: each column's printed figure, and whether it is the default."""
    tables = report_tables((speed_vs_error_report / "speed-vs-error.md").read_text(encoding="utf-8"))
    header, *rows = tables["Aerodynamics (ClutterFly-v1)"]
    out = {}
    for cells in rows:
        label = cells[0].strip("*")
        name = label.removesuffix(" (default)").removesuffix(" (reference)")
        out[name] = {"default": label.endswith("(default)"),
                     **{column: float(cell.replace(",", "")) for column, cell in zip(header[1:-1], cells[1:-1])}}
    return header, out


def test_the_reference_costs_nothing_and_every_partial_model_costs_error(aero):
    _, rows = aero
    assert list(rows) == list(SETTINGS)
    assert rows["drag + ground_effect"]["max error (mm)"] == 0.0
    for name in SETTINGS[:-1]:
        assert rows[name]["max error (mm)"] > 0.1 and rows[name]["mean error (mm)"] > 0.0, name
    assert [r["default"] for r in rows.values()] == [True, False, False, False]
    assert all(r["steps per CPU-s"] > 0 for r in rows.values())


def test_drag_matters_in_the_fast_cruise_and_ground_effect_near_the_floor(aero):
    _, rows = aero
    no_drag, no_ground_effect = rows["ground_effect"], rows["drag"]
    assert no_drag["cruise max (mm)"] > 1.5 * no_drag["low max (mm)"]
    assert no_ground_effect["low max (mm)"] > 100 * no_ground_effect["cruise max (mm)"]


def test_only_ground_effect_lifts_a_hover_by_the_model_gain_at_its_rotor_hubs(aero):
    header, rows = aero
    low, spawn = (column for column in header if column.startswith("hover lift at "))
    low_z = 1e-3 * float(re.search(r"at ([\d.]+) mm", low).group(1))  # the low flight's start
    spawn_z = float(re.search(r"at ([\d.]+) m ", spawn).group(1))  # the lowest height scenes spawn at
    assert spawn_z == pytest.approx(0.5)
    hub = 0.018  # rotor hubs above the base origin (assets/robots/quadrotor.urdf)
    gain = ground_effect_gain(np.array([low_z + hub, spawn_z + hub]), quadrotor_model().rotor_radius)
    for name, r in rows.items():
        lift_low, lift_spawn = r[low] / 100, r[spawn] / 100  # per cent of g in the table
        if "ground_effect" in name:
            assert lift_low == pytest.approx(gain[0] - 1.0, rel=0.02)
            assert lift_spawn == pytest.approx(gain[1] - 1.0, rel=0.02)
        else:
            assert abs(lift_low) < 1e-6 and abs(lift_spawn) < 1e-6
