"""What every robot spec reader does first: check the keys, find the URDF, prepare and parse it; and read numbers,
joint lists and mounts with errors that name the field."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from clutter_gym.collision.kinematics import UrdfKinematics
from clutter_gym.collision.urdf_geometry import CollisionElement, load_collision_elements
from clutter_gym.robots.spec_paths import SHARED_KEYS, spec_name, spec_package_roots
from clutter_gym.robots.urdf_prep import Mount, prepared_urdf
from clutter_gym.util.checks import short_repr


@dataclass(frozen=True, eq=False)
class SpecUrdf:
    """A spec's URDF: the user's file (``source``), the prepared copy the env loads (``urdf``), its kinematics and
    collision elements, and the robot's name."""

    source: Path
    urdf: Path
    kinematics: UrdfKinematics
    elements: list[CollisionElement]
    name: str


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
    """The spec's URDF prepared with ``mounts`` and parsed; a URDF the parser refuses is reported as such."""
    source = spec_source(spec, where, folder)
    name, roots = spec_name(spec, where, source), spec_package_roots(spec, where, folder)
    try:
        urdf = prepared_urdf(source, name, mounts, roots)
        return SpecUrdf(source, urdf, UrdfKinematics(urdf), load_collision_elements(urdf), name)
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


def numbers(value: object, n: int, where: str, low: float, high: float) -> list[float]:
    """``value`` as ``n`` finite numbers in [low, high], or an error naming ``where`` and the range."""
    try:
        out = [float(v) for v in value]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        out = []
    if len(out) != n or not all(math.isfinite(v) and low <= v <= high for v in out):
        raise ValueError(f"{where} must be {n} number{'s' if n > 1 else ''} in [{low:g}, {high:g}], got "
                         f"{short_repr(value)}")
    return out


def number(spec: Mapping[str, object], key: str, where: str, default: float, low: float, high: float) -> float:
    """``spec[key]`` (``default`` if absent) as one number in [low, high]."""
    if key not in spec and not math.isfinite(default):
        raise ValueError(f"{where}: {key} is needed: it cannot be read from the URDF")
    value = spec.get(key, default)
    try:
        return numbers([value], 1, "", low, high)[0]
    except ValueError:
        raise ValueError(f"{where}: {key} must be a number in [{low:g}, {high:g}], got {short_repr(value)}") from None


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
