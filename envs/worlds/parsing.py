"""The user-scene parsing every world shares: reset options, scene keys, lists of numbers and obstacles, whose
errors name the field and its allowed range.

The obstacle format is one for every world: upright boxes and cylinders; ``position`` is the centre of the
footprint, ``z`` the height of the bottom face (0 = on the floor or the table), sizes are full extents, metres and
radians in the world frame. An obstacle with a ``mass`` is movable: it starts at that pose, at rest, and the physics
moves it when it is pushed; one without stays where it is put.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.checks import is_number

SHAPES = ("box", "cylinder")
MAX_OBSTACLE_HEIGHT = 5.0  # metres; anything taller only costs render time
MASS_RANGE = (1e-3, 1e3)  # kg of a movable obstacle: from a gram to a tonne
L = TypeVar("L")  # a layout: one world's scene type
RESET_OPTIONS = ("scene",)


def check_reset_options(options: Any) -> Mapping[str, Any]:
    """``reset`` options as a mapping ({} for None); unknown keys raise ``ValueError`` naming them."""
    options = options or {}
    if not isinstance(options, Mapping):
        raise ValueError(f"reset options must be a dict, got {type(options).__name__}")
    unknown = set(options) - set(RESET_OPTIONS)
    if unknown:
        raise ValueError(f"unknown reset options {sorted(unknown)}; allowed: {list(RESET_OPTIONS)}")
    return options


def scene_from_options(options: Any, parse: Callable[[Any], L], sample: Callable[[], L]) -> L:
    """An arena's ``choose_scene``: ``parse(options["scene"])`` if the options hold a user scene, else
    ``sample()``, the seeded random layout.

    Raises:
        ValueError: unknown option keys, or what ``parse`` raises for a malformed scene.
    """
    options = check_reset_options(options)
    if "scene" in options:
        return parse(options["scene"])
    return sample()


def check_scene_keys(spec: Any, keys: Sequence[str]) -> Mapping[str, Any]:
    """A user scene as a mapping whose keys are among ``keys``; otherwise a ``ValueError`` naming the allowed keys."""
    if not isinstance(spec, Mapping):
        raise ValueError(f"scene must be a dict with keys {', '.join(map(repr, keys))}, got {type(spec).__name__}")
    unknown = set(spec) - set(keys)
    if unknown:
        raise ValueError(f"scene has unknown keys {sorted(unknown)}; allowed: {sorted(keys)}")
    return spec


def parse_numbers(value: Any, n: int, field: str, what: str) -> tuple[float, ...]:
    """``value`` (a sequence or a 1-D array) as a tuple of ``n`` finite floats; errors name ``field`` and say
    ``what`` the numbers are."""
    if isinstance(value, np.ndarray) and value.ndim == 1:
        value = value.tolist()
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or len(value) != n:
        raise ValueError(f"{field} must be a list of {n} numbers ({what}), got {value!r}")
    try:
        out = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{field} must be a list of {n} numbers ({what}), got {value!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise ValueError(f"{field} must be finite, got {value!r}")
    return out


def _number(value: Any, field: str, lo: float, hi: float, what: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{field} must be a number ({what}), got {value!r}") from None
    if not (math.isfinite(out) and lo < out <= hi):
        raise ValueError(f"{field} must be in ({lo}, {hi}] ({what}), got {value!r}")
    return out


def check_inside(point: Sequence[float], field: str, limit: float) -> None:
    """|x| and |y| of ``point`` within ``limit`` metres; else a ``ValueError`` naming ``field``."""
    if max(abs(point[0]), abs(point[1])) > limit:
        raise ValueError(
            f"{field} must lie inside the arena: |x|, |y| <= {limit:.3f} m, got ({point[0]}, {point[1]})"
        )


def parse_obstacle(spec: Any, field: str, arena_size: float) -> Obstacle:
    """One obstacle from its dict form; errors name ``field`` and the allowed values."""
    if not isinstance(spec, Mapping):
        raise ValueError(f"{field} must be a dict with a 'shape' key, got {spec!r}")
    shape = spec.get("shape")
    allowed = {"box": {"shape", "size", "position", "yaw", "z", "mass"},
               "cylinder": {"shape", "radius", "height", "position", "z", "mass"}}
    if shape not in allowed:
        raise ValueError(f"{field}.shape must be one of {SHAPES}, got {shape!r}")
    unknown = set(spec) - allowed[shape]
    if unknown:
        raise ValueError(f"{field} has unknown keys {sorted(unknown)}; a {shape} takes {sorted(allowed[shape])}")
    missing = (allowed[shape] - {"yaw", "z", "mass"}) - set(spec)
    if missing:
        raise ValueError(f"{field} is missing {sorted(missing)}")
    position = parse_numbers(spec["position"], 2, f"{field}.position", "x, y in metres")
    check_inside(position, f"{field}.position", 0.5 * arena_size)
    z = float(spec.get("z", 0.0)) if is_number(spec.get("z", 0.0)) else math.nan
    if not 0.0 <= z <= MAX_OBSTACLE_HEIGHT:
        raise ValueError(f"{field}.z (bottom height) must be in [0, {MAX_OBSTACLE_HEIGHT}] m, got {spec.get('z')!r}")
    mass = _mass(spec.get("mass", 0.0), f"{field}.mass")
    if shape == "box":
        size = parse_numbers(spec["size"], 3, f"{field}.size", "full extents sx, sy, sz in metres")
        for axis, v in zip("xyz", size):
            limit = MAX_OBSTACLE_HEIGHT if axis == "z" else arena_size
            if not 0.0 < v <= limit:
                raise ValueError(f"{field}.size {axis} must be in (0, {limit}] m, got {v}")
        yaw = _number(spec.get("yaw", 0.0), f"{field}.yaw", -math.inf, math.inf, "radians")
        return Obstacle("box", size, position, yaw, z, mass)
    radius = _number(spec["radius"], f"{field}.radius", 0.0, 0.5 * arena_size, "metres")
    height = _number(spec["height"], f"{field}.height", 0.0, MAX_OBSTACLE_HEIGHT, "metres")
    return Obstacle("cylinder", (2 * radius, 2 * radius, height), position, 0.0, z, mass)


def _mass(value: Any, field: str) -> float:
    """An obstacle's mass: 0 (static) or within :data:`MASS_RANGE` kg."""
    lo, hi = MASS_RANGE
    mass = float(value) if is_number(value) else math.nan
    if not (mass == 0.0 or lo <= mass <= hi):
        raise ValueError(f"{field} must be 0 (static) or in [{lo:g}, {hi:g}] kg (movable), got {value!r}")
    return mass


def parse_obstacles(raw: Any, arena_size: float) -> tuple[Obstacle, ...]:
    """A scene's ``obstacles`` list (see :func:`parse_obstacle`); errors name ``scene.obstacles[i]``."""
    if isinstance(raw, (str, bytes, Mapping)) or not isinstance(raw, Sequence):
        raise ValueError(f"scene.obstacles must be a list of obstacle dicts, got {raw!r}")
    return tuple(parse_obstacle(o, f"scene.obstacles[{i}]", arena_size) for i, o in enumerate(raw))
