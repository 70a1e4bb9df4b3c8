"""``python -m benchmarks.hard_cases.catalogue``: a cheap case's row is finite and within its bound, and a case
name that is not in the registry is refused with the names that are."""

from __future__ import annotations

import math

import pytest

from benchmarks.hard_cases.catalogue import CASES, main, run_case


@pytest.mark.parametrize("name", ["mass-1kg-on-1t", "scale-drive"])
def test_a_cheap_case_is_finite_and_within_its_bound(name):
    row, seconds = run_case(name, quick=True)
    assert row.case == name
    assert math.isfinite(row.figure) and row.figure >= 0.0
    assert row.bound is not None and row.within, row.markdown()
    assert math.isfinite(row.rate) and row.rate > 0.0
    assert row.markdown().startswith(f"| {name} | ") and row.markdown().count(" | ") == 4
    assert seconds < 30.0


def test_one_case_prints_one_row(capsys):
    rows = main(["--quick", "--case", "mass-1kg-on-1t"])
    assert [r.case for r in rows] == ["mass-1kg-on-1t"]
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("| case | error figure | bound it is tested against | steps/s | settings |")
    assert lines[2] == rows[0].markdown()


def test_an_unknown_case_is_refused_naming_the_cases(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--case", "no-such-case"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'no-such-case'" in err
    assert all(name in err for name in CASES)
