"""Argument checks the parts share: one message form, numpy scalars accepted wherever Python numbers are, bad values
shown cut short, and names that may become part of a path."""

from __future__ import annotations

import numbers
import re
import reprlib
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
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {short_repr(value)}")
    return int(value)


def check_fraction(name: str, value: Any) -> float:
    """``value`` as a float when it is a number in [0, 1]; else a ValueError naming ``name`` and the range."""
    if not (is_number(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"{name} must be a number in [0, 1], got {short_repr(value)}")
    return float(value)


_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxstring, _SHORT.maxother = 3, 60, 60
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxset = _SHORT.maxfrozenset = _SHORT.maxdeque = _SHORT.maxarray = 6
_SHORT.maxdict = 4
#: characters: the most of a value an error message shows
SHORT_REPR = 160


def short_repr(value: Any) -> str:
    """``repr(value)`` cut to :data:`SHORT_REPR` characters, looking at only a few elements per level: a bad value
    in a message names itself without costing what the whole repr would (a YAML file's aliases can make a value of
    a few hundred bytes stand for gigabytes of text)."""
    try:
        text = _SHORT.repr(value)
    except Exception:  # a repr that raises (an int past Python's digit limit, a broken object) still names its type
        text = f"<{type(value).__name__}>"
    return text if len(text) <= SHORT_REPR else text[:SHORT_REPR - 3] + "..."


#: a plain file name: 1 to 64 letters, digits, '.', '_' or '-', not starting with '.' (so never '.', '..' or hidden)
FILE_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,63}")


def check_file_name(name: str, value: Any) -> str:
    """``value`` when it is a plain file name (:data:`FILE_NAME`): no folder separators, no ``..``, no NUL, at most
    64 characters, so it can become part of a path without leaving its folder; else a ValueError naming ``name``."""
    if not (isinstance(value, str) and FILE_NAME.fullmatch(value)):
        raise ValueError(f"{name} must be a plain file name: 1 to 64 letters, digits, '.', '_' or '-', not starting "
                         f"with '.', got {short_repr(value)}")
    return value
