"""What every task's reward shares: the range check of its weights, the terms that price safety and effort, and the
split of a step's safety cost by cause."""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any

import numpy as np


def check_weights(weights: Any) -> None:
    """Raise ``ValueError`` naming the first field of the dataclass ``weights`` outside [0, 1e4] (signs are the
    terms' own: a weight only scales its term)."""
    for name, value in asdict(weights).items():
        if not (math.isfinite(value) and 0.0 <= value <= 1e4):
            raise ValueError(f"reward weight {name} must be in [0, 1e4], got {value!r}")


def clearance_term(weight: float, margin: float, min_clearance: float) -> float:
    """``-weight`` times the shortfall of ``min_clearance`` below ``margin`` as a fraction of it (capped at 1);
    0 with no margin."""
    if not margin:
        return 0.0
    return -weight * min(1.0, max(0.0, margin - min_clearance) / margin)


def control_term(weight: float, action: np.ndarray) -> float:
    """``-weight`` times the squared norm of the (clipped) action."""
    return -weight * float(action @ action)


def cost_by_cause(**causes: bool) -> dict[str, float]:
    """A step's safety cost split by cause, Safety-Gymnasium style: 1.0 for the first cause that holds, in the order
    given, 0.0 for the others, so the values sum to the step's cost (1 for an unsafe step, else 0). Every cause has
    its entry in every step."""
    costs = dict.fromkeys(causes, 0.0)
    first = next((name for name, holds in causes.items() if holds), None)
    if first is not None:
        costs[first] = 1.0
    return costs
