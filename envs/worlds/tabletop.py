"""A table in front of a fixed arm, crowded with boxes, cylinders and a shelf: seeded layouts and user scenes.

Frame: the arm's base at the origin, the table top at z = -TABLE_GAP (the base stands on a mounting plate that
is not modelled, so the fixed base never "touches" the table), x forward, z up. Obstacles stand on the table
(``z`` = 0) or, for shelf boards, on the shelf's sides.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.sim import Sim
from clutter_gym.util.checks import check_fraction, check_integer
from clutter_gym.worlds.parsing import check_scene_keys, parse_numbers, parse_obstacles, scene_from_options
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.sampling import polyline_distances, with_masses

TABLE_GAP = 0.005
TABLE = Obstacle("box", (1.6, 1.8, 0.05), (0.4, 0.0), 0.0, -0.05 - TABLE_GAP)
REACH_RADIUS = 0.8  # metres from the shoulder (0, 0, 0.333) within which targets are drawn
SHOULDER = np.array([0.0, 0.0, 0.333])
TABLE_LIMIT = 0.8  # |x|, |y| of user obstacles and targets, metres
#: The rgb_array view (:meth:`TabletopArena.render_camera`), world frame, metres.
VIEW_EYE, VIEW_TARGET = (1.1, -0.8, 0.8), (0.3, 0.0, 0.3)
ARM_KEEP_OUT = 0.15  # generated obstacles keep this far from the vertical plane of the start pose's arm, metres


@dataclass(frozen=True)
class TableSpec:
    """Layout parameters.

    Attributes:
        n_obstacles: boxes and cylinders on the table, [0, 20].
        shelf: place a shelf (back, two sides, a middle board and a top) on the table.
        shelf_target_probability: chance that the target is inside the shelf, [0, 1].
        start_noise: uniform noise on each joint of the ready pose at the start, radians, [0, 0.5].
        target_clearance: least distance from the target to any obstacle, metres.
        movable_fraction: fraction of the boxes and cylinders (not the shelf) that are movable, in [0, 1].
        movable_density: kg/m^3 of movable clutter, that of packed groceries: a few hundred grams an object.
    """

    n_obstacles: int = 6
    shelf: bool = True
    shelf_target_probability: float = 0.3
    start_noise: float = 0.1
    target_clearance: float = 0.06
    movable_fraction: float = 0.0
    movable_density: float = 300.0

    def __post_init__(self) -> None:
        check_integer("n_obstacles", self.n_obstacles, 0, 20)
        if not 0.0 <= self.shelf_target_probability <= 1.0:
            raise ValueError(f"shelf_target_probability must be in [0, 1], got {self.shelf_target_probability!r}")
        if not 0.0 <= self.start_noise <= 0.5:
            raise ValueError(f"start_noise must be in [0, 0.5] rad, got {self.start_noise!r}")
        check_fraction("movable_obstacles", self.movable_fraction)


@dataclass(frozen=True)
class ReachScene:
    """One layout: obstacles on the table, the arm's start joint positions and the target point."""

    obstacles: tuple[Obstacle, ...]
    start: tuple[float, ...]
    target: tuple[float, float, float]

    def to_dict(self) -> dict[str, Any]:
        """The reset-options format: ``env.reset(options={"scene": scene.to_dict()})`` reproduces it."""
        return {"obstacles": [o.to_dict() for o in self.obstacles], "start": list(self.start),
                "target": list(self.target)}


def shelf_parts(centre: tuple[float, float], yaw: float, width: float = 0.4, depth: float = 0.25,
                height: float = 0.45, board: float = 0.2, thick: float = 0.02) -> tuple[Obstacle, ...]:
    """A shelf open towards -x of its own frame (rotated by ``yaw``), as five boxes."""
    c, s = math.cos(yaw), math.sin(yaw)

    def at(dx: float, dy: float) -> tuple[float, float]:
        return (centre[0] + c * dx - s * dy, centre[1] + s * dx + c * dy)

    half_d, half_w = 0.5 * depth, 0.5 * width
    return (
        Obstacle("box", (thick, width, height), at(half_d - 0.5 * thick, 0.0), yaw),
        Obstacle("box", (depth, thick, height), at(0.0, half_w - 0.5 * thick), yaw),
        Obstacle("box", (depth, thick, height), at(0.0, -half_w + 0.5 * thick), yaw),
        Obstacle("box", (depth - thick, width - 2 * thick, thick), at(-0.5 * thick, 0.0), yaw, board),
        Obstacle("box", (depth, width, thick), at(0.0, 0.0), yaw, height),
    )


def point_clearance(point: np.ndarray, obstacles: Sequence[Obstacle]) -> float:
    """Distance (metres) from ``point`` to the nearest obstacle, negative inside one."""
    return min((o.distance3d(point) for o in obstacles), default=math.inf)


def sample_reach_scene(rng: np.random.Generator, spec: TableSpec, ready: Sequence[float],
                       shoulder: Sequence[float] = SHOULDER, reach: float = REACH_RADIUS) -> ReachScene:
    """A seeded layout: shelf, clutter clear of the start pose's arm, start pose and a target within ``reach``
    metres of ``shoulder`` (the Panda's by default)."""
    obstacles: list[Obstacle] = []
    footprints: list[tuple[np.ndarray, float]] = []  # (centre, radius) of every placed footprint
    arm = np.array([[0.0, 0.0], [0.45, 0.0]])
    shelf_compartments: list[tuple[np.ndarray, float]] = []
    if spec.shelf:
        angle = rng.uniform(-1.1, 1.1)
        angle += math.copysign(0.35, angle)  # keep the shelf off the arm's start plane
        r = rng.uniform(0.55, 0.7)
        centre = (r * math.cos(angle), r * math.sin(angle))
        parts = shelf_parts(centre, angle)
        obstacles.extend(parts)
        footprints.append((np.array(centre), 0.25))
        for low, high in ((0.0, 0.2), (0.22, 0.45)):  # two compartments: (centre, height)
            inner = np.array(centre) - 0.02 * np.array([math.cos(angle), math.sin(angle)])
            shelf_compartments.append((np.array([*inner, 0.5 * (low + high)]), high - low))
    tries = 0
    while len(obstacles) < spec.n_obstacles + (5 if spec.shelf else 0) and tries < 200:
        tries += 1
        r, angle = rng.uniform(0.3, 0.75), rng.uniform(-2.0, 2.0)
        xy = np.array([r * math.cos(angle), r * math.sin(angle)])
        if rng.uniform() < 0.5:
            size = (float(rng.choice([0.05, 0.08, 0.12])), float(rng.choice([0.05, 0.08, 0.12])),
                    float(rng.choice([0.08, 0.15, 0.25, 0.35])))
            candidate = Obstacle("box", size, (float(xy[0]), float(xy[1])), float(rng.uniform(-math.pi, math.pi)))
        else:
            radius = float(rng.choice([0.03, 0.045, 0.06]))
            height = float(rng.choice([0.1, 0.2, 0.3]))
            candidate = Obstacle("cylinder", (2 * radius, 2 * radius, height), (float(xy[0]), float(xy[1])))
        extent = candidate.radius
        if polyline_distances(xy[None], arm)[0] < extent + ARM_KEEP_OUT:
            continue
        if any(np.linalg.norm(xy - c) < extent + rc + 0.02 for c, rc in footprints):
            continue
        obstacles.append(candidate)
        footprints.append((xy, extent))
    start = tuple(float(v) for v in np.asarray(ready) + rng.uniform(-spec.start_noise, spec.start_noise,
                                                                    size=len(ready)))
    target = _sample_target(rng, spec, tuple(obstacles), shelf_compartments, np.asarray(shoulder), reach)
    clutter = range(5 if spec.shelf else 0, len(obstacles))  # the shelf is furniture: it stays put
    return ReachScene(with_masses(obstacles, clutter, spec.movable_fraction, spec.movable_density), start, target)


def _sample_target(rng: np.random.Generator, spec: TableSpec, obstacles: tuple[Obstacle, ...],
                   compartments: list[tuple[np.ndarray, float]], shoulder: np.ndarray,
                   reach: float) -> tuple[float, float, float]:
    if compartments and rng.uniform() < spec.shelf_target_probability:
        centre, _ = compartments[int(rng.integers(len(compartments)))]
        return tuple(float(v) for v in centre)
    for _ in range(1000):
        p = np.array([rng.uniform(0.15, 0.75), rng.uniform(-0.6, 0.6), rng.uniform(0.05, 0.55)])
        if np.linalg.norm(p - shoulder) > reach or np.hypot(p[0], p[1]) < 0.3:
            continue
        if point_clearance(p, obstacles) >= spec.target_clearance:
            return tuple(float(v) for v in p)
    raise RuntimeError("no free target point found in 1000 draws; lower n_obstacles")


def parse_reach_scene(spec: Any, n_joints: int, lower: np.ndarray, upper: np.ndarray,
                      shoulder: Sequence[float] = SHOULDER, reach: float = REACH_RADIUS) -> ReachScene:
    """Validate a user scene (``reset(options={"scene": ...})``): obstacles, start joint positions, target.

    Raises:
        ValueError: naming the offending field and its allowed range.
    """
    spec = check_scene_keys(spec, ("obstacles", "start", "target"))
    if "target" not in spec:
        raise ValueError("scene.target is required (x, y, z in metres)")
    obstacles = parse_obstacles(spec.get("obstacles", []), 2 * TABLE_LIMIT)
    target = parse_numbers(spec["target"], 3, "scene.target", "x, y, z in metres")
    if np.linalg.norm(np.array(target) - np.asarray(shoulder)) > reach + 0.1:
        raise ValueError(f"scene.target {target} is beyond the arm's reach: at most {reach + 0.1:g} m from "
                         f"the shoulder {np.asarray(shoulder).tolist()}")
    start = (parse_numbers(spec.get("start", ()), n_joints, "scene.start", "joint positions in rad")
             if "start" in spec else None)
    if start is not None:
        for i, (v, lo, hi) in enumerate(zip(start, lower, upper)):
            if not lo <= v <= hi:
                raise ValueError(f"scene.start[{i}] must be in [{lo}, {hi}] rad (the joint's limits), got {v}")
    return ReachScene(obstacles, start, target)


class TabletopArena:
    """The table (built once) and the pooled clutter of one env.

    Args:
        spec: layout parameters.
        ready: the arm's ready joint positions (start poses are drawn around it; a user scene without a start
            gets it exactly).
        lower, upper: joint limits, for validating user start poses.
        shoulder, reach: targets are drawn (and user targets accepted) within ``reach`` metres of ``shoulder``.
    """

    def __init__(self, spec: TableSpec, ready: Sequence[float], lower: np.ndarray, upper: np.ndarray,
                 shoulder: np.ndarray | Sequence[float] = SHOULDER, reach: float = REACH_RADIUS) -> None:
        self.spec = spec
        self.ready = tuple(ready)
        self._lower, self._upper = lower, upper
        self._shoulder, self._reach = tuple(float(v) for v in shoulder), float(reach)
        self._pool: ObstaclePool | None = None

    def load(self, sim: Sim) -> None:
        """Create the table (once per env)."""
        self._pool = ObstaclePool(sim, (TABLE,))

    @property
    def pool_size(self) -> int:
        return self._pool.size

    def choose_scene(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> ReachScene:
        """The user's scene from ``options["scene"]`` if given, else a seeded random layout.

        Raises:
            ValueError: unknown option keys or a malformed scene (the message names the field).
        """
        return scene_from_options(
            options, parse=self._parse,
            sample=lambda: sample_reach_scene(rng, self.spec, self.ready, self._shoulder, self._reach)
        )

    def _parse(self, spec: Any) -> ReachScene:
        """A user scene; one without a start begins at the ready pose."""
        scene = parse_reach_scene(spec, len(self.ready), self._lower, self._upper, self._shoulder, self._reach)
        return scene if scene.start is not None else ReachScene(scene.obstacles, self.ready, scene.target)

    def place(self, scene: ReachScene) -> tuple[tuple[Obstacle, ...], list[int]]:
        """Move pooled bodies into ``scene``; returns every obstacle (the table included) and its body ids."""
        bodies = self._pool.place(scene.obstacles)
        return scene.obstacles + self._pool.fixed, bodies + self._pool.fixed_bodies

    def render_camera(self, sim: Sim, robot: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eye, target) of the rgb_array view: a fixed view of the arm's workspace from the front right, near
        enough for the hand and the target to read, with the arm's usual poses in frame (both are ringed, also when
        the shelf or the arm hides them). It casts no rays."""
        return np.array(VIEW_EYE), np.array(VIEW_TARGET)
