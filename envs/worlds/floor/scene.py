"""Floor scenes as plain data: obstacles, the robot's start (x, y, yaw) and the goal (x, y); the parser of user
scenes, whose errors name the field.

Coordinates are metres in the world frame: the arena is the square [-L/2, L/2]^2 on the floor (z = 0), walled on
all four sides. The obstacle format is every world's (``worlds/parsing.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.parsing import check_inside, check_scene_keys, parse_numbers, parse_obstacles

if TYPE_CHECKING:
    from clutter_gym.worlds.floor.grid import ClearanceGrid


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
    check_inside(start, "scene.start", 0.5 * arena_size - robot_radius)
    check_inside(goal, "scene.goal", 0.5 * arena_size)
    scene = Scene(obstacles, start, goal)
    clearance = scene.clearance(start[0], start[1], arena_size)
    if clearance < robot_radius:
        raise ValueError(
            f"scene.start ({start[0]}, {start[1]}) is {clearance:.3f} m from the nearest obstacle or wall; "
            f"the robot needs at least its footprint radius {robot_radius} m"
        )
    return scene
