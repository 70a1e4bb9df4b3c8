"""Validated parameter blocks for noise models: every field declares its unit and allowed range.

A noise section is a frozen dataclass whose fields are made with :func:`param`. Construction checks every value
against its range and raises a ``ValueError`` that names the field (``lidar.range_sigma``), the allowed range and
the unit, so a typo in a profile override fails at ``gym.make`` time, not deep inside a step.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from typing import Any, ClassVar, TypeVar

from clutter_gym.util.checks import is_integer, is_number

P = TypeVar("P", bound="NoiseParams")


def param(default: float, lo: float, hi: float, unit: str = "", doc: str = "", integer: bool = False) -> Any:
    """A dataclass field for a float (or integer) parameter allowed in the closed interval [lo, hi]."""
    return dataclasses.field(default=default, metadata={"range": (lo, hi), "unit": unit, "doc": doc, "int": integer})


def choice(default: str, options: tuple[str, ...], doc: str = "") -> Any:
    """A dataclass field for a string parameter that must be one of ``options``."""
    return dataclasses.field(default=default, metadata={"options": options, "doc": doc})


@dataclasses.dataclass(frozen=True)
class NoiseParams:
    """Base of every noise section. Subclasses set ``section`` (the name used in profiles and error messages)."""

    section: ClassVar[str] = "noise"

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            name = f"{self.section}.{f.name}"
            if "options" in f.metadata:
                if value not in f.metadata["options"]:
                    raise ValueError(f"{name} must be one of {f.metadata['options']}, got {value!r}")
                continue
            lo, hi = f.metadata["range"]
            unit = f" {f.metadata['unit']}" if f.metadata["unit"] else ""
            if f.metadata["int"]:
                if not (is_integer(value) and lo <= value <= hi):
                    raise ValueError(f"{name} must be an integer in [{lo}, {hi}]{unit}, got {value!r}")
                object.__setattr__(self, f.name, int(value))
                continue
            ok = is_number(value) and math.isfinite(value)
            if not (ok and lo <= value <= hi):
                raise ValueError(f"{name} must be a number in [{lo}, {hi}]{unit}, got {value!r}")
            object.__setattr__(self, f.name, float(value))

    @classmethod
    def from_dict(cls: type[P], values: Mapping[str, Any]) -> P:
        """Build from a mapping, rejecting unknown keys with the list of allowed ones."""
        if not isinstance(values, Mapping):
            raise ValueError(f"noise section {cls.section!r} must be a mapping of parameters, got {values!r}")
        allowed = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(values) - set(allowed))
        if unknown:
            raise ValueError(f"unknown {cls.section} noise parameters {unknown}; allowed: {allowed}")
        return cls(**values)

    def replace(self: P, values: Mapping[str, Any]) -> P:
        """A copy with some parameters overridden (same checks as :meth:`from_dict`)."""
        return type(self).from_dict({**dataclasses.asdict(self), **values})

    @functools.cached_property
    def is_clean(self) -> bool:
        """True when every parameter is at its default (the defaults of every section mean "no noise")."""
        return all(getattr(self, f.name) == f.default for f in dataclasses.fields(self))
