"""A walled arena with pooled clutter: chooses each episode's scene and puts it into the Sim."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.sim import Sim
from clutter_gym.util.camera_view import fitting_distance
from clutter_gym.worlds.floor.sample import sample_scene
from clutter_gym.worlds.floor.scene import Scene, parse_scene
from clutter_gym.worlds.floor.spec import ClutterSpec
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.pooled_arena import PooledArena

#: The rgb_array view (:meth:`ClutterArena.render_camera`): its angle above the floor, how far inside the frame's
#: edges it keeps the robot and the goal (a fraction of the half-frame), the nearest it comes (metres), and the
#: frame size it is fitted for (pixels: only its shape matters).
VIEW_ELEVATION = math.radians(65.0)
VIEW_INSET = 0.3
NEAREST_VIEW = 2.5
VIEW_SIZE = (320, 240)


def arena_walls(arena: float, height: float, thick: float) -> tuple[Obstacle, ...]:
    """The four walls around the square [-arena/2, arena/2]^2."""
    half, span = 0.5 * arena, arena + 2 * thick
    return (
        Obstacle("box", (span, thick, height), (0.0, half + 0.5 * thick)),
        Obstacle("box", (span, thick, height), (0.0, -half - 0.5 * thick)),
        Obstacle("box", (thick, span, height), (half + 0.5 * thick, 0.0)),
        Obstacle("box", (thick, span, height), (-half - 0.5 * thick, 0.0)),
    )


class ClutterArena(PooledArena[Scene]):
    """Ground plane, four walls and the obstacle pool of one env.

    Args:
        spec: layout parameters (arena size, density, size ranges).
        robot_radius: footprint radius used for reachability and start checks, metres.
    """

    def __init__(self, spec: ClutterSpec, robot_radius: float) -> None:
        self.spec = spec
        self.robot_radius = robot_radius

    def load(self, sim: Sim) -> None:
        """Create the ground and walls (once per env)."""
        sim.add_ground(visual_size=self.spec.arena_size + 2.0)
        walls = arena_walls(self.spec.arena_size, self.spec.obstacle_height, self.spec.wall_thickness)
        self._pool = ObstaclePool(sim, walls)

    @property
    def walls(self) -> tuple[Obstacle, ...]:
        return self._pool.fixed

    def _parse(self, raw: Any) -> Scene:
        return parse_scene(raw, self.spec.arena_size, self.robot_radius)

    def _sample(self, rng: np.random.Generator) -> Scene:
        return sample_scene(rng, self.spec, self.robot_radius)

    def render_camera(self, sim: Sim, robot: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eye, target) of the rgb_array view: from the -y side, :data:`VIEW_ELEVATION` above the floor, aimed
        midway between the robot and the goal on the floor, as near as keeps both :data:`VIEW_INSET` inside the
        frame's edges, yet never nearer than :data:`NEAREST_VIEW` (the robot readable when close to the goal) nor
        further than the whole arena needs. It casts no rays."""
        centre = np.array([0.5 * (robot[0] + goal[0]), 0.5 * (robot[1] + goal[1]), 0.0])
        direction = np.array([0.0, -math.cos(VIEW_ELEVATION), math.sin(VIEW_ELEVATION)])
        farthest = 0.94 * self.spec.arena_size  # the whole arena in view
        points = np.array([robot, goal], dtype=float)
        distance = fitting_distance(points, centre, direction, NEAREST_VIEW, farthest, *VIEW_SIZE, VIEW_INSET)
        return centre + distance * direction, centre
