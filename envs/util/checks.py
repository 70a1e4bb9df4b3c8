"""Argument checks the parts share: one message form, and numpy scalars accepted wherever Python numbers are."""

from __future__ import annotations

import numbers
from typing import Any, TypeGuard

import numpy as np


def is_number(value: Any) -> TypeGuard[float]:
    """An int, float or numpy number, not a bool (to a type checker: a float, which all of these act as)."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def is_integer(value: Any) -> bool:
    """An int or numpy integer, not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def check_integer(name: str, value: Any, lo: int, hi: int) -> int:
    """``value`` as an int when it is an integer in [lo, hi]; else a ValueError naming ``name`` and the range."""
    if not (is_integer(value) and lo <= value <= hi):
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")
    return int(value)


def check_fraction(name: str, value: Any) -> float:
    """``value`` as a float when it is a number in [0, 1]; else a ValueError naming ``name`` and the range."""
    if not (is_number(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"{name} must be a number in [0, 1], got {value!r}")
    return float(value)
