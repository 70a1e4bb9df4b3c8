"""Table scenes as plain data: obstacles on the table, the arm's start joint positions and the target point; the
parser of user scenes, whose errors name the field. Coordinates are metres in the frame of ``worlds/table/spec.py``;
the obstacle format is every world's (``worlds/parsing.py``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.parsing import check_scene_keys, parse_numbers, parse_obstacles

TABLE_LIMIT = 0.8  # |x|, |y| of user obstacles and targets, metres


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


def point_clearance(point: np.ndarray, obstacles: Sequence[Obstacle]) -> float:
    """Distance (metres) from ``point`` to the nearest obstacle, negative inside one."""
    return min((o.distance3d(point) for o in obstacles), default=math.inf)


def parse_reach_scene(spec: Any, n_joints: int, lower: np.ndarray, upper: np.ndarray,
                      shoulder: Sequence[float], reach: float) -> ReachScene:
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
