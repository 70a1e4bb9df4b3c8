"""Full command into a corner and into a gap narrower than the robot for 60 s: the simulation stays sane.

Measured: worst penetration 0.09 mm (corner) and 0.38 mm (gap), speed 0 once wedged, every value finite. The
bounds: penetration under 1 mm (a contact, not a tunnel), speed never above the commanded maximum (no energy
gained from the contacts), contacts and cost in agreement on every step.
"""

from __future__ import annotations

import pytest

from benchmarks.hard_cases.scenes.wedging import WEDGES, wedge


@pytest.mark.parametrize("name", WEDGES)
def test_full_command_into_a_trap_for_a_minute(name):
    run = wedge(name, seconds=60.0)
    assert run.finite and run.mismatched == 0  # every observation and reward finite; contacts iff cost, every step
    assert run.touched > 0  # it did reach the trap
    assert run.final_x < 1.0 if name == "gap" else run.final_x > 2.0  # and stayed in it
    assert run.penetration < 1e-3
    assert run.fastest <= 0.5 * 1.01  # max_linear_speed
    assert run.final_speed < 1e-3  # wedged, not jittering
