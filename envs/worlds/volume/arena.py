"""The ClutterFly world in the Sim: floor, four walls and an optional ceiling around the volume, pooled clutter."""

from __future__ import annotations

from typing import Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.sim import Sim
from clutter_gym.util.camera_view import between, chase_eye, pull_in
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.pooled_arena import PooledArena
from clutter_gym.worlds.volume.sample import sample_volume_scene
from clutter_gym.worlds.volume.scene import VolumeScene, parse_volume_scene
from clutter_gym.worlds.volume.spec import VolumeSpec

BOUNDARY_THICKNESS = 0.1  # metres of the walls and the ceiling, outside the volume
#: The rgb_array chase camera (:meth:`VolumeArena.render_camera`): metres behind and above the robot, how far towards
#: the goal it aims (0: at the robot, 1: at the goal), how far in front of an obstacle its spring arm stops and the
#: shortest the arm gets, metres.
CHASE_BACK, CHASE_UP = 0.55, 0.35
CHASE_GOAL_WEIGHT = 0.35
CHASE_MARGIN, CHASE_SHORTEST = 0.08, 0.2


def volume_boundary(spec: VolumeSpec) -> tuple[Obstacle, ...]:
    """The walls just outside the volume's four sides, from the floor to its top (to the ceiling's top with one),
    and the ceiling on top of it when ``spec.ceiling`` is on; world frame, metres."""
    sx, sy, sz = spec.size
    t = BOUNDARY_THICKNESS
    height = sz + t if spec.ceiling else sz
    walls = (
        Obstacle("box", (sx + 2 * t, t, height), (0.0, 0.5 * (sy + t))),
        Obstacle("box", (sx + 2 * t, t, height), (0.0, -0.5 * (sy + t))),
        Obstacle("box", (t, sy + 2 * t, height), (0.5 * (sx + t), 0.0)),
        Obstacle("box", (t, sy + 2 * t, height), (-0.5 * (sx + t), 0.0)),
    )
    return (*walls, Obstacle("box", (sx + 2 * t, sy + 2 * t, t), (0.0, 0.0), 0.0, sz)) if spec.ceiling else walls


def floor_slab(spec: VolumeSpec) -> tuple[Obstacle, ...]:
    """The floor as an obstacle: a slab under the whole volume and its walls whose top face is the ground plane
    z = 0 (world frame, metres)."""
    sx, sy, _ = spec.size
    t = BOUNDARY_THICKNESS
    return (Obstacle("box", (sx + 2 * t, sy + 2 * t, t), (0.0, 0.0), 0.0, -t),)


class VolumeArena(PooledArena[VolumeScene]):
    """Floor, boundary and the obstacle pool of one env (the ``Arena`` contract of ``clutter_gym.interfaces``).

    Args:
        spec: the volume and its layout parameters.
        robot_radius: bounding radius of the robot, metres, for reachability and the start check.
        floor_obstacle: count the floor among the obstacles :meth:`place` returns (:func:`floor_slab`, paired with
            the ground plane's body), so that the collision checker measures a flying robot's clearance to the
            floor and reports touching it as a contact; a robot that stands on the floor leaves it out.
    """

    def __init__(self, spec: VolumeSpec, robot_radius: float, floor_obstacle: bool = False) -> None:
        self.spec = spec
        self.robot_radius = robot_radius
        self.floor_obstacle = bool(floor_obstacle)
        self._ground = -1

    def load(self, sim: Sim) -> None:
        """Create the floor and the boundary (once per built world)."""
        self._ground = sim.add_ground(visual_size=max(self.spec.size[:2]) + 2.0)
        self._pool = ObstaclePool(sim, volume_boundary(self.spec))

    def _parse(self, raw: Any) -> VolumeScene:
        return parse_volume_scene(raw, self.spec, self.robot_radius)

    def _sample(self, rng: np.random.Generator) -> VolumeScene:
        return sample_volume_scene(rng, self.spec, self.robot_radius)

    def place(self, scene: VolumeScene) -> tuple[tuple[Obstacle, ...], list[int]]:
        """Move pooled bodies into ``scene``; returns every obstacle (the boundary included, and the floor with
        ``floor_obstacle``) and its body ids."""
        obstacles, bodies = super().place(scene)
        if self.floor_obstacle:
            return obstacles + floor_slab(self.spec), [*bodies, self._ground]
        return obstacles, bodies

    def render_camera(self, sim: Sim, robot: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eye, target) of the rgb_array view: a chase camera :data:`CHASE_BACK` behind the robot (away from the
        goal) and :data:`CHASE_UP` above it, aimed between the robot and the goal (:data:`CHASE_GOAL_WEIGHT`). A
        spring arm keeps it in front of whatever stands between the robot and that place: one ray from the robot
        (which rays pass through) to the eye, and the eye pulled in :data:`CHASE_MARGIN` short of the hit, so the
        robot is never hidden behind a wall, the ceiling or clutter."""
        robot = np.asarray(robot, dtype=float)
        eye = chase_eye(robot, goal, CHASE_BACK, CHASE_UP)
        (free,) = sim.rays.ray_hit_fractions([robot.tolist()], [eye.tolist()])
        eye = pull_in(robot, eye, float(free), CHASE_MARGIN, CHASE_SHORTEST)
        return eye, between(robot, goal, eye, CHASE_GOAL_WEIGHT)
