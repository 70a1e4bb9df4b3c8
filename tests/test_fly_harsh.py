"""benchmarks.learning.fly_harsh for one episode a cell: its columns are harsh's parts, and a cell flies the flyer
it names."""

from __future__ import annotations

from dataclasses import asdict

from benchmarks.learning.fly_harsh import COLUMNS, ROWS, cell
from clutter_gym.noise.profiles import resolve_noise


def test_the_columns_are_harshs_parts_taken_from_the_profile():
    harsh = resolve_noise("harsh")
    assert COLUMNS["command delay (2 steps)"]["action"] == {"latency_steps": harsh.action.latency_steps}
    assert COLUMNS["command noise"]["action"] == {"sigma": harsh.action.sigma}
    assert COLUMNS["dynamics"]["dynamics"] == asdict(harsh.dynamics)
    assert [reads for _, reads, _ in ROWS] == [False, True, False, True]


def test_a_cell_flies_one_episode_per_layout():
    rows = cell(True, 4.0, COLUMNS["dynamics"], 1)
    assert len(rows) == 1 and rows[0]["success"] in (0.0, 1.0) and rows[0]["length"] > 0
