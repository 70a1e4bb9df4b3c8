"""A choice a user makes, measured: its settings' speed and error, the Pareto front, and its plot."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from clutter_gym.training.figures import plt, save_figure


@dataclass
class Row:
    """One setting: its speed (a rate or a time, see :class:`Choice`), its error, and extra columns.

    ``selectable`` is False for a reference shown beside the settings (another library), which is left out of the
    Pareto front."""

    label: str
    speed: float
    error: float
    default: bool
    extra: dict[str, float] = field(default_factory=dict)
    selectable: bool = True


@dataclass
class Choice:
    """A setting's rows, how they were measured and why the default is the default.

    ``rate`` tells whether ``speed`` is a rate (higher is faster) or a time per call (lower is faster)."""

    key: str
    title: str
    setting: str
    speed_label: str
    rate: bool
    error_label: str
    rows: list[Row]
    method: str
    why: str

    def faster(self, a: Row, b: Row) -> bool:
        """``a`` is at least as fast as ``b``."""
        return a.speed >= b.speed if self.rate else a.speed <= b.speed

    def pareto(self) -> set[str]:
        """Labels of the selectable rows that no other selectable row beats on both speed and error."""
        rows = [r for r in self.rows if r.selectable]
        return {r.label for r in rows
                if not any(o is not r and self.faster(o, r) and o.error <= r.error
                           and (o.speed != r.speed or o.error < r.error) for o in rows)}


def plot_choice(choice: Choice, path: Path) -> Path:
    """Error against speed, the Pareto front joined, the default starred, every point labelled."""
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    front = choice.pareto()
    on_front = sorted((r for r in choice.rows if r.label in front), key=lambda r: r.speed)
    ax.plot([r.speed for r in on_front], [r.error for r in on_front], "-", color="0.7", zorder=1,
            label="Pareto front")
    for r in choice.rows:
        style = dict(marker="*", markersize=14, color="tab:red") if r.default else \
            dict(marker="o", markersize=6, color="tab:blue" if r.selectable else "tab:gray")
        ax.plot([r.speed], [r.error], linestyle="none", zorder=2, **style)
        ax.annotate(r.label + (" (default)" if r.default else ""), (r.speed, r.error), textcoords="offset points",
                    xytext=(4, 4), fontsize=7)
    speeds = [r.speed for r in choice.rows]
    if max(speeds) > 10 * min(speeds):
        ax.set_xscale("log")
    errors = [r.error for r in choice.rows if r.error > 0]
    if errors and max(errors) > 30 * min(errors):
        ax.set_yscale("symlog", linthresh=min(errors))
    ax.set_xlabel(choice.speed_label + (" (higher is faster)" if choice.rate else " (lower is faster)"))
    ax.set_ylabel(choice.error_label)
    ax.set_title(choice.title, fontsize=10)
    ax.legend(fontsize=7)
    return save_figure(fig, path)
