"""What every robot spec reader does first: read the spec file, check the keys, find the URDF, prepare and parse it;
and read numbers, joint lists and mounts with errors that name the field (and, for a value the spec left out, say
that it was derived from the URDF and how)."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.robots.spec_paths import SHARED_KEYS, spec_name, spec_package_roots
from clutter_gym.robots.urdf_prep import Mount, prepared_urdf
from clutter_gym.urdf.geometry import CollisionElement, load_collision_elements, parse_urdf
from clutter_gym.urdf.kinematics import UrdfKinematics
from clutter_gym.util.checks import is_number, short_repr
from clutter_gym.util.safe_yaml import read_yaml

#: A number in exponent notation with no dot or no exponent sign (3e-8, 1.0e3): YAML 1.2 reads it as a number, but
#: PyYAML (YAML 1.1) leaves it a string, so a spec file's number may arrive as this text. No other text is a number.
_EXPONENT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")


@dataclass(frozen=True, eq=False)
class SpecUrdf:
    """A spec's URDF: the user's file (``source``), the prepared copy the env loads (``urdf``), its kinematics and
    collision elements, the robot's name, and the masses the user's file gives its links (kg; a link without an
    ``<inertial>`` is left out: the prepared copy gives it a token gram)."""

    source: Path
    urdf: Path
    kinematics: UrdfKinematics
    elements: list[CollisionElement]
    name: str
    masses: dict[str, float]


def read_spec_file(path: Path) -> Mapping[str, object]:
    """The mapping of keys a YAML spec file holds, read with the bounded loader (:mod:`clutter_gym.util.safe_yaml`).

    Raises:
        ValueError: the file is not UTF-8 text, not YAML, over the loader's bounds, or not a mapping (one line naming
            the file).
    """
    spec = read_yaml(path, f"robot spec file {path}")
    if not isinstance(spec, Mapping):
        raise ValueError(f"robot spec {path}: expected a mapping of keys, got {type(spec).__name__}")
    return spec


def check_keys(spec: Mapping[str, object], keys: Sequence[str], required: int, kind: str, where: str) -> None:
    """Refuse keys outside ``keys`` (and ``kind`` and the keys every kind takes) and a missing one of the first
    ``required``."""
    a = "an" if kind[0] in "aeiou" else "a"
    unknown = sorted(set(spec) - set(keys) - {"kind", *SHARED_KEYS}, key=str)
    if unknown:
        raise ValueError(f"{where}: unknown keys {short_repr(unknown)}; {a} {kind} spec takes "
                         f"{list(keys) + list(SHARED_KEYS)}")
    for key in keys[:required]:
        if key not in spec:
            raise ValueError(f"{where}: missing {key!r} ({a} {kind} spec needs {list(keys[:required])})")


def spec_source(spec: Mapping[str, object], where: str, folder: Path | None) -> Path:
    """The spec's ``urdf``, relative to ``folder`` (the spec file's) unless absolute."""
    source = Path(str(spec["urdf"])).expanduser()
    if not source.is_absolute() and folder is not None:
        source = folder / source
    if not source.is_file():
        raise ValueError(f"{where}: urdf {str(source)!r} is not a file")
    return source


def load_spec_urdf(spec: Mapping[str, object], where: str, folder: Path | None,
                   mounts: tuple[Mount, ...]) -> SpecUrdf:
    """The spec's URDF prepared with ``mounts`` and parsed; a URDF the parser refuses (``urdf/checks.py``
    says what it refuses) is reported as such, and so is one whose links weigh nothing in all: pybullet would fly or
    drive the prepared copy's token grams."""
    source = spec_source(spec, where, folder)
    name, roots = spec_name(spec, where, source), spec_package_roots(spec, where, folder)
    try:
        masses = {str(link.get("name")): float(mass.get("value", "nan")) for link in parse_urdf(source).findall("link")
                  if (mass := link.find("inertial/mass")) is not None}
        if not sum(masses.values()) > 0.0:
            given = f"gives its links {sum(masses.values()):g} kg in all" if masses else "has no <inertial> element"
            raise ValueError(f"{source} {given}, so the robot's mass and inertia are unknown (pybullet would take a "
                             "token gram a link): give each link an <inertial> with its mass and inertia")
        urdf = prepared_urdf(source, name, mounts, roots)
        return SpecUrdf(source, urdf, UrdfKinematics(urdf), load_collision_elements(urdf), name, masses)
    except ValueError as error:
        raise ValueError(f"{where}: the URDF was refused: {error}") from None


def joint_names(spec: Mapping[str, object], key: str, urdf: SpecUrdf, where: str, low: int = 1,
                high: int = 16) -> tuple[str, ...]:
    """``spec[key]``: a list of ``low`` to ``high`` names of the URDF's moving joints."""
    joints = spec[key]
    if isinstance(joints, str) or not isinstance(joints, (list, tuple)) or not low <= len(joints) <= high:
        raise ValueError(f"{where}: {key} must be a list of {low} to {high} joint names, got {short_repr(joints)}")
    moving = [j.name for j in urdf.kinematics.joints]
    missing = [j for j in joints if j not in moving]
    if missing:
        raise ValueError(f"{where}: {key} names {missing}, not moving joints of {urdf.source}; its moving joints: "
                         f"{moving}")
    return tuple(str(j) for j in joints)


def as_number(value: object) -> float | None:
    """``value`` as a float when it is a number (not a bool: ``true`` is not 1 metre), or text YAML 1.2 reads as a
    number and PyYAML leaves a string (exponent notation, :data:`_EXPONENT`); else None."""
    if is_number(value):
        return float(value)
    if isinstance(value, str) and _EXPONENT.fullmatch(value.strip()):
        return float(value)
    return None


def numbers(value: object, n: int, where: str, low: float, high: float) -> list[float]:
    """``value`` as ``n`` finite numbers in [low, high], or an error naming ``where`` and the range."""
    items = list(value) if isinstance(value, (list, tuple, np.ndarray)) else []
    out = [as_number(v) for v in items]
    if len(out) != n or not all(v is not None and math.isfinite(v) and low <= v <= high for v in out):
        raise ValueError(f"{where} must be {n} number{'s' if n > 1 else ''} in [{low:g}, {high:g}], got "
                         f"{short_repr(value)}{_typed(value)}")
    return [v for v in out if v is not None]  # all of them: None was refused above


def _typed(value: object) -> str:
    """What a message adds when ``value`` is (or holds) text or a boolean, which are not numbers here."""
    items = value if isinstance(value, (list, tuple)) else [value]
    return " (text and true/false are not numbers)" if any(isinstance(v, (str, bool)) for v in items) else ""


def number(spec: Mapping[str, object], key: str, where: str, default: float, low: float, high: float,
           derived: str = "") -> float:
    """``spec[key]`` (``default`` if absent) as one number in [low, high]. ``derived`` says how ``default`` was read
    from the URDF, for the error when the spec leaves ``key`` out and the URDF gives none, or one out of range."""
    if key not in spec:
        if derived and not low <= default <= high:  # nan included
            found = "none" if math.isnan(default) else f"{default:.4g}, outside [{low:g}, {high:g}]"
            raise ValueError(f"{where}: {key} was not given, and reading it from {derived} gives {found}: give {key} "
                             "in the spec")
        if not math.isfinite(default):
            raise ValueError(f"{where}: {key} is needed: it cannot be read from the URDF")
    value = spec.get(key, default)
    try:
        return numbers([value], 1, "", low, high)[0]
    except ValueError:
        raise ValueError(f"{where}: {key} must be a number in [{low:g}, {high:g}], got "
                         f"{short_repr(value)}{_typed(value)}") from None


def spec_mounts(spec: Mapping[str, object], where: str) -> tuple[Mount, ...]:
    """The links a spec's ``mounts`` (``{link: {"parent": ..., "xyz": [...], "rpy": [...]}}``) adds, if any."""
    mounts = spec.get("mounts") or {}
    if not isinstance(mounts, Mapping):
        raise ValueError(f"{where}: mounts must be a mapping of link names to mounts, got {short_repr(mounts)}")
    return tuple(mount(str(link), entry, f"{where}: mounts.{link}") for link, entry in mounts.items())


def mount(link: str, entry: object, where: str) -> Mount:
    """A link to add, from ``{"parent": link, "xyz": [...], "rpy": [...]}``."""
    if not isinstance(entry, Mapping) or "parent" not in entry:
        raise ValueError(f"{where} must be a mapping with a 'parent' link, got {short_repr(entry)}")
    unknown = set(entry) - {"parent", "xyz", "rpy"}
    if unknown:
        raise ValueError(f"{where} has unknown keys {sorted(unknown)}; allowed: parent, xyz, rpy")
    xyz = numbers(entry.get("xyz", (0, 0, 0)), 3, f"{where}.xyz", -1e3, 1e3)
    rpy = numbers(entry.get("rpy", (0, 0, 0)), 3, f"{where}.rpy", -1e3, 1e3)
    return Mount(link, str(entry["parent"]), tuple(xyz), tuple(rpy))  # type: ignore[arg-type]
