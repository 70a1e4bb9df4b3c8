"""Worlds: scenes as plain data, seeded clutter layouts, and the body pool that puts a scene into a Sim."""

from clutter_gym.worlds.arena import ClutterArena
from clutter_gym.worlds.clutter import ClutterSpec, sample_scene
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.scene import Obstacle, Scene, parse_scene
from clutter_gym.worlds.tabletop import ReachScene, TableSpec, TabletopArena, sample_reach_scene

__all__ = [
    "ClutterArena",
    "ClutterSpec",
    "Obstacle",
    "ObstaclePool",
    "ReachScene",
    "Scene",
    "TableSpec",
    "TabletopArena",
    "parse_scene",
    "sample_reach_scene",
    "sample_scene",
]
