"""``python -m benchmarks.hard_cases.catalogue``, run as a user runs it: cheap cases print one finite row each,
within its bound, and a case name that is not in the registry is refused with the names that are."""

from __future__ import annotations

import math
import re

import pytest
from helpers import ROOT, markdown_rows, run_benchmark

CHEAP = ("mass-1kg-on-1t", "scale-drive")
HEADER = ["case", "error figure", "bound it is tested against", "steps/s", "settings"]


def summary_cases() -> list[str]:
    """The case names of docs/hard-cases.md's summary table (the catalogue's --quick output)."""
    page = (ROOT / "docs" / "hard-cases.md").read_text(encoding="utf-8")
    section = page.split("\n## Summary run\n", 1)[1].split("\n## ", 1)[0]
    return [cells[0] for cells in markdown_rows(section) if cells != HEADER]


@pytest.fixture(scope="module")
def cheap():
    return run_benchmark("benchmarks.hard_cases.catalogue", "--quick", "--case", *CHEAP)


def test_cheap_cases_print_one_finite_row_each_within_its_bound(cheap):
    assert cheap.returncode == 0, cheap.stderr[-3000:]
    header, *rows = markdown_rows(cheap.stdout)
    assert header == HEADER
    assert [cells[0] for cells in rows] == list(CHEAP)
    for _, figure, bound, rate, _ in rows:
        value, per_second = float(figure.split()[0]), float(rate.split()[0].replace(",", ""))
        assert math.isfinite(value) and value >= 0.0, figure
        assert re.fullmatch(r"≤ \S+ \S+, met \(.+\)", bound), bound  # a bound, and the figure within it
        assert math.isfinite(per_second) and per_second > 0.0, rate
    seconds = re.search(r"^2 cases in \d+ s \(--quick\): (.*)$", cheap.stdout, flags=re.M).group(1)
    assert all(float(s.split()[-2]) < 30.0 for s in seconds.split(", ")), seconds


def test_an_unknown_case_is_refused_naming_the_cases():
    refused = run_benchmark("benchmarks.hard_cases.catalogue", "--case", "no-such-case")
    assert refused.returncode == 2
    assert "invalid choice: 'no-such-case'" in refused.stderr
    cases = summary_cases()
    assert len(cases) > 20 and all(f"'{name}'" in refused.stderr for name in cases), refused.stderr
