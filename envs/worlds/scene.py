"""Scenes as plain data: obstacles, start and goal; parsing and validation of user-given scenes, with the
helpers every world's parser and ``choose_scene`` share (``worlds/tabletop.py`` uses them too).

Coordinates are metres in the world frame: the arena is the square [-L/2, L/2]^2 on the floor (z = 0), walled on
all four sides. Obstacles are upright boxes and cylinders; ``position`` is the centre of the footprint, ``z`` the
height of the bottom face (0 = on the floor), sizes are full extents. An obstacle with a ``mass`` is movable: it
starts at that pose, at rest, and the physics moves it when it is pushed; one without stays where it is put.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.checks import is_number

if TYPE_CHECKING:
    from clutter_gym.worlds.clutter import ClearanceGrid

SHAPES = ("box", "cylinder")
MAX_OBSTACLE_HEIGHT = 5.0  # metres; anything taller only costs render time
MASS_RANGE = (1e-3, 1e3)  # kg of a movable obstacle: from a gram to a tonne
L = TypeVar("L")  # a layout: a Scene, or another world's scene type


def with_masses(obstacles: Sequence[Obstacle], eligible: Sequence[int], fraction: float,
                density: float) -> tuple[Obstacle, ...]:
    """``obstacles`` with the first ``round(fraction * len(eligible))`` of the ``eligible`` ones (indices) made
    movable at ``density`` kg/m^3 (each mass clipped to :data:`MASS_RANGE`).

    A generated layout lists its obstacles in random order, so the first ones are a random subset, and the
    layout itself is the same whatever the fraction: no random number is drawn here.
    """
    chosen = eligible[:round(fraction * len(eligible))]
    if not chosen:
        return tuple(obstacles)
    out = list(obstacles)
    for i in chosen:
        mass = float(min(max(density * out[i].volume, MASS_RANGE[0]), MASS_RANGE[1]))
        out[i] = dataclasses.replace(out[i], mass=mass)
    return tuple(out)


def polyline_distances(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """(n,) distance from each of ``points`` (n, 2) to the polyline through ``polyline`` (k, 2), k >= 2."""
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    t = np.einsum("nsd,sd->ns", points[:, None, :] - a[None], ab) / np.maximum(np.einsum("sd,sd->s", ab, ab), 1e-12)
    nearest = a[None] + np.clip(t, 0.0, 1.0)[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - nearest, axis=2).min(axis=1)


@dataclass(frozen=True)
class Scene:
    """One layout: obstacles, robot start (x, y, yaw) and goal (x, y).

    ``clearance_grid`` is not part of the layout (``==``, ``repr`` and :meth:`to_dict` ignore it): the clearance
    field the generator sampled start and goal on, kept so that the path-distance grid need not compute it again;
    None for a scene made any other way.
    """

    obstacles: tuple[Obstacle, ...]
    start: tuple[float, float, float]
    goal: tuple[float, float]
    clearance_grid: ClearanceGrid | None = field(default=None, compare=False, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """The reset-options format: ``env.reset(options={"scene": scene.to_dict()})`` reproduces it."""
        return {"obstacles": [o.to_dict() for o in self.obstacles], "start": list(self.start),
                "goal": list(self.goal)}

    def clearance(self, x: float, y: float, arena_size: float) -> float:
        """Distance (metres) from point (x, y) to the nearest obstacle footprint or arena wall."""
        half = 0.5 * arena_size
        d = min(half - abs(x), half - abs(y))
        for o in self.obstacles:
            d = min(d, float(o.distance(np.array(x), np.array(y))))
        return d


# ------------------------------------------------------------------------------------------------ parsing
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


def _inside(point: Sequence[float], field: str, limit: float) -> None:
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
    _inside(position, f"{field}.position", 0.5 * arena_size)
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


def parse_scene(spec: Any, arena_size: float, robot_radius: float) -> Scene:
    """Validate a user scene (the ``reset(options={"scene": ...})`` format) and turn it into a :class:`Scene`.

    The start must leave the robot's footprint clear of every obstacle and wall; reachability of the goal is
    the user's choice and is not checked.

    Raises:
        ValueError: naming the offending field and its allowed range.
    """
    spec = check_scene_keys(spec, ("obstacles", "start", "goal"))
    for key in ("start", "goal"):
        if key not in spec:
            raise ValueError(f"scene.{key} is required")
    obstacles = parse_obstacles(spec.get("obstacles", []), arena_size)
    start = parse_numbers(spec["start"], 3, "scene.start", "x, y in metres and yaw in radians")
    goal = parse_numbers(spec["goal"], 2, "scene.goal", "x, y in metres")
    _inside(start, "scene.start", 0.5 * arena_size - robot_radius)
    _inside(goal, "scene.goal", 0.5 * arena_size)
    scene = Scene(obstacles, start, goal)
    clearance = scene.clearance(start[0], start[1], arena_size)
    if clearance < robot_radius:
        raise ValueError(
            f"scene.start ({start[0]}, {start[1]}) is {clearance:.3f} m from the nearest obstacle or wall; "
            f"the robot needs at least its footprint radius {robot_radius} m"
        )
    return scene
