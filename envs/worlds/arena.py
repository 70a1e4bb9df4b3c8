"""A walled arena with pooled clutter: chooses each episode's scene and puts it into the Sim."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from clutter_gym.sim import Sim
from clutter_gym.worlds.clutter import ClutterSpec, sample_scene
from clutter_gym.worlds.pool import ObstaclePool, arena_walls
from clutter_gym.worlds.scene import Obstacle, Scene, parse_scene, scene_from_options


class ClutterArena:
    """Ground plane, four walls and the obstacle pool of one env.

    Args:
        spec: layout parameters (arena size, density, size ranges).
        robot_radius: footprint radius used for reachability and start checks, metres.
    """

    def __init__(self, spec: ClutterSpec, robot_radius: float) -> None:
        self.spec = spec
        self.robot_radius = robot_radius
        self._pool: ObstaclePool | None = None

    def load(self, sim: Sim) -> None:
        """Create the ground and walls (once per env)."""
        sim.add_ground(visual_size=self.spec.arena_size + 2.0)
        walls = arena_walls(self.spec.arena_size, self.spec.obstacle_height, self.spec.wall_thickness)
        self._pool = ObstaclePool(sim, walls)

    @property
    def walls(self) -> tuple[Obstacle, ...]:
        return self._pool.fixed

    @property
    def pool_size(self) -> int:
        return self._pool.size

    def choose_scene(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> Scene:
        """The user's scene from ``options["scene"]`` if given, else a seeded random layout.

        Raises:
            ValueError: unknown option keys or a malformed scene (the message names the field).
        """
        return scene_from_options(
            options,
            parse=lambda spec: parse_scene(spec, self.spec.arena_size, self.robot_radius),
            sample=lambda: sample_scene(rng, self.spec, self.robot_radius),
        )

    def overview_camera(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(eye, target) of the rgb_array view."""
        a = self.spec.arena_size
        return (0.0, -0.62 * a, 0.78 * a), (0.0, -0.1 * a, 0.0)

    def place(self, scene: Scene) -> tuple[tuple[Obstacle, ...], list[int]]:
        """Move pooled bodies into ``scene``; returns every obstacle (walls included) and its body ids."""
        bodies = self._pool.place(scene.obstacles)
        return scene.obstacles + self.walls, bodies + self._pool.fixed_bodies
