"""The aerodynamics section of the speed-against-error report measures something: each effect left out costs
error where it should, the reference costs none, and only ground effect changes the hover thrust."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.speed import aero_cost
from clutter_gym.robots import QuadrotorConfig
from clutter_gym.robots.aero import ground_effect_gain


@pytest.fixture(scope="module")
def rows():
    """One timing round of short flights: the cruise reaches 3 m/s, the low flight is still over the floor."""
    return {r["aero"]: r for r in aero_cost.rows(rounds=1, steps=(30, 30))}


def test_the_reference_costs_nothing_and_every_partial_model_costs_error(rows):
    assert rows[aero_cost.REFERENCE]["error_mm"] == 0.0
    for aero in aero_cost.SETTINGS[:-1]:
        assert rows[aero]["error_mm"] > 0.1 and rows[aero]["mean_mm"] > 0.0, aero
    assert [r["default"] for r in rows.values()] == [True, False, False, False]
    assert all(r["rate"] > 0 for r in rows.values())


def test_drag_matters_in_the_fast_cruise_and_ground_effect_near_the_floor(rows):
    no_drag, no_ground_effect = rows[("ground_effect",)], rows[("drag",)]
    assert no_drag["cruise_mm"] > 1.5 * no_drag["low_mm"]
    assert no_ground_effect["low_mm"] > 100 * no_ground_effect["cruise_mm"]


def test_only_ground_effect_lifts_a_hover_by_the_model_gain_at_its_rotor_hubs(rows):
    hub = 0.018  # rotor hubs above the base origin (assets/robots/quadrotor.urdf)
    radius = QuadrotorConfig().rotor_radius
    for aero, r in rows.items():
        if "ground_effect" in aero:
            gain = ground_effect_gain(np.array([aero_cost.LOW_START_Z + hub, r["spawn_height"] + hub]), radius)
            assert r["lift_low"] == pytest.approx(gain[0] - 1.0, rel=0.02)
            assert r["lift_spawn"] == pytest.approx(gain[1] - 1.0, rel=0.02)
        else:
            assert abs(r["lift_low"]) < 1e-6 and abs(r["lift_spawn"]) < 1e-6
    assert rows[()]["spawn_height"] == pytest.approx(0.5)
