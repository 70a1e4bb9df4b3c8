"""Matplotlib figures written headless (Agg) and atomically."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from clutter_gym.util.atomic import atomic_path  # noqa: E402


def save_figure(fig: plt.Figure, path: Path) -> Path:
    """Lay out, write (temp file + rename) and close ``fig``."""
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path
