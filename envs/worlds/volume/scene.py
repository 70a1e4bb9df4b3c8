"""ClutterFly scenes as plain data: obstacles in a volume, a start pose (x, y, z, yaw) and a goal point (x, y, z);
the parser of user scenes, whose errors name the field.

The obstacle format is every world's (``worlds/parsing.py``) unchanged: upright boxes and cylinders with ``z``
the height of their bottom face, so a horizontal beam is a long thin box lifted by ``z`` and turned by ``yaw``,
and a wall with an opening is the boxes around the opening. Only start and goal gain a z. Coordinates are metres in
the world frame of ``worlds/volume/spec.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.parsing import check_scene_keys, parse_numbers, parse_obstacles
from clutter_gym.worlds.volume.spec import VolumeSpec

if TYPE_CHECKING:
    from clutter_gym.worlds.volume.grid import VolumeGrid

SCENE_KEYS = ("obstacles", "start", "goal")


@dataclass(frozen=True)
class VolumeScene:
    """One layout: obstacles, the robot's start (x, y, z, yaw) and the goal (x, y, z), world frame, metres and
    radians.

    ``grid`` is not part of the layout (``==``, ``repr`` and :meth:`to_dict` ignore it): the clearance grid the
    generator drew start and goal on, kept so that the path distance need not compute it again; None for a scene
    made any other way.
    """

    obstacles: tuple[Obstacle, ...]
    start: tuple[float, float, float, float]
    goal: tuple[float, float, float]
    grid: VolumeGrid | None = field(default=None, compare=False, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """The reset-options format: ``env.reset(options={"scene": scene.to_dict()})`` reproduces it."""
        return {"obstacles": [o.to_dict() for o in self.obstacles], "start": list(self.start),
                "goal": list(self.goal)}


def boundary_distance(point: tuple[float, ...] | np.ndarray, spec: VolumeSpec) -> float:
    """Distance (metres) from ``point`` (x, y, z) to the nearest face of the volume (walls, floor, top);
    negative outside."""
    sx, sy, sz = spec.size
    return min(0.5 * sx - abs(point[0]), 0.5 * sy - abs(point[1]), point[2], sz - point[2])


def point_clearance(point: tuple[float, ...] | np.ndarray, obstacles: tuple[Obstacle, ...], spec: VolumeSpec) -> float:
    """Distance (metres) from ``point`` (x, y, z) to the nearest obstacle or face of the volume; negative inside."""
    p = np.asarray(point[:3], dtype=float)
    return min([boundary_distance(p, spec), *(o.distance3d(p) for o in obstacles)])


def _check_inside(o: Obstacle, name: str, spec: VolumeSpec) -> None:
    """An obstacle's footprint centre and bottom lie inside the volume; else a ValueError naming ``name``."""
    sx, sy, sz = spec.size
    if abs(o.position[0]) > 0.5 * sx or abs(o.position[1]) > 0.5 * sy:
        raise ValueError(f"{name}.position must lie inside the volume: |x| <= {0.5 * sx:g}, |y| <= {0.5 * sy:g} m, "
                         f"got {o.position}")
    if o.z > sz:
        raise ValueError(f"{name}.z (bottom height) must be in [0, {sz:g}] m (inside the volume), got {o.z}")


def parse_volume_scene(raw: Any, spec: VolumeSpec, robot_radius: float) -> VolumeScene:
    """Validate a user scene (the ``reset(options={"scene": ...})`` format) and turn it into a :class:`VolumeScene`.

    Numbers may be numpy scalars and lists numpy arrays. The start must leave a sphere of ``robot_radius`` clear of
    every obstacle and face of the volume; the goal must lie inside the volume. Reachability of a user's goal is
    the user's choice and is not checked.

    Raises:
        ValueError: naming the offending field and its allowed range.
    """
    raw = check_scene_keys(raw, SCENE_KEYS)
    for key in ("start", "goal"):
        if key not in raw:
            raise ValueError(f"scene.{key} is required")
    obstacles = parse_obstacles(raw.get("obstacles", []), max(spec.size[:2]))
    for i, o in enumerate(obstacles):
        _check_inside(o, f"scene.obstacles[{i}]", spec)
    start = parse_numbers(raw["start"], 4, "scene.start", "x, y, z in metres and yaw in radians")
    goal = parse_numbers(raw["goal"], 3, "scene.goal", "x, y, z in metres")
    sx, sy, sz = spec.size
    if boundary_distance(goal, spec) < 0.0:
        raise ValueError(f"scene.goal must lie inside the volume: |x| <= {0.5 * sx:g}, |y| <= {0.5 * sy:g}, "
                         f"0 <= z <= {sz:g} m, got {goal}")
    clearance = point_clearance(start, obstacles, spec)
    if not clearance >= robot_radius:
        raise ValueError(
            f"scene.start ({start[0]}, {start[1]}, {start[2]}) is {clearance:.3f} m from the nearest obstacle or "
            f"face of the volume; the robot needs at least its radius {robot_radius} m"
        )
    return VolumeScene(obstacles, start, goal)
