"""``python -m benchmarks.learning.fly_harsh`` for one episode a cell, run as a user runs it: its columns are
harsh's parts, taken from the profile, its rows read the thrust estimate where they say so, and every cell flies
its episode."""

from __future__ import annotations

import json
from dataclasses import asdict

from helpers import markdown_rows, run_benchmark

from clutter_gym.noise.profiles import resolve_noise

PARTS = ("command delay (2 steps)", "command noise", "dynamics")


def test_each_part_of_harsh_is_a_column_every_row_flies(tmp_path):
    run = run_benchmark("benchmarks.learning.fly_harsh", "--episodes", "1", "--workers", "2", "--out", str(tmp_path),
                        "--columns", *PARTS)
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads((tmp_path / "fly_harsh.json").read_text())
    harsh, columns = resolve_noise("harsh"), report["columns"]
    assert list(columns) == list(PARTS)
    assert columns["command delay (2 steps)"]["action"] == {"latency_steps": harsh.action.latency_steps}
    assert columns["command noise"]["action"] == {"sigma": harsh.action.sigma}
    assert columns["dynamics"]["dynamics"] == asdict(harsh.dynamics)
    assert [row["thrust_estimate"] for row in report["rows"].values()] == [False, True, False, True]
    assert list(report["cells"]) == list(report["rows"])
    for cells in report["cells"].values():
        assert list(cells) == list(PARTS)
        for (episode,) in cells.values():
            assert episode["success"] in (0.0, 1.0) and episode["length"] > 0
    header, *rows = markdown_rows(run.stdout)
    assert header == ["flyer on the subgoal", *(f"`{part}`" for part in PARTS)]
    assert [cells[0] for cells in rows] == list(report["rows"])
