"""The speed-against-error report's pieces: Pareto fronts for rates and times, plots."""

from __future__ import annotations

from benchmarks.choice import Choice, Row, plot_choice


def choice(rate: bool, rows: list[Row]) -> Choice:
    return Choice("k", "title", "`x`", "speed", rate, "error", rows, "method", "why")


def test_pareto_front_of_times_keeps_only_undominated_rows():
    rows = [Row("fast, rough", 1.0, 10.0, False), Row("slow, exact", 10.0, 0.0, True),
            Row("dominated", 5.0, 12.0, False), Row("middle", 3.0, 4.0, False),
            Row("reference", 0.5, 0.0, False, selectable=False)]
    assert choice(False, rows).pareto() == {"fast, rough", "slow, exact", "middle"}


def test_pareto_front_of_rates_prefers_higher_rates():
    rows = [Row("a", 100.0, 1.0, True), Row("b", 200.0, 1.0, False), Row("c", 50.0, 0.5, False)]
    assert choice(True, rows).pareto() == {"b", "c"}


def test_equal_rows_do_not_dominate_each_other():
    rows = [Row("a", 1.0, 1.0, True), Row("b", 1.0, 1.0, False)]
    assert choice(False, rows).pareto() == {"a", "b"}


def test_plot_writes_a_png(tmp_path):
    rows = [Row("a", 1.0, 0.0, True), Row("b", 100.0, 5.0, False), Row("ref", 3.0, 2.0, False, selectable=False)]
    path = plot_choice(choice(False, rows), tmp_path / "c.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
