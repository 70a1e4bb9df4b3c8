"""The range check every task's reward-weights dataclass runs on construction."""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any


def check_weights(weights: Any) -> None:
    """Raise ``ValueError`` naming the first field of the dataclass ``weights`` outside [0, 1e4] (signs are the
    terms' own: a weight only scales its term)."""
    for name, value in asdict(weights).items():
        if not (math.isfinite(value) and 0.0 <= value <= 1e4):
            raise ValueError(f"reward weight {name} must be in [0, 1e4], got {value!r}")
