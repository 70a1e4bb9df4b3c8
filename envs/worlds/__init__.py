"""Worlds: scenes as plain data, seeded clutter layouts (the floor, the table, the ClutterFly volume), and the body
pool that puts a scene into a Sim."""

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.floor.arena import ClutterArena
from clutter_gym.worlds.floor.sample import sample_scene
from clutter_gym.worlds.floor.scene import Scene, parse_scene
from clutter_gym.worlds.floor.spec import ClutterSpec
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.table.arena import TabletopArena
from clutter_gym.worlds.table.sample import sample_reach_scene
from clutter_gym.worlds.table.scene import ReachScene
from clutter_gym.worlds.table.spec import TableSpec
from clutter_gym.worlds.volume.arena import VolumeArena
from clutter_gym.worlds.volume.path import VolumePathDistance
from clutter_gym.worlds.volume.sample import sample_volume_scene
from clutter_gym.worlds.volume.scene import VolumeScene, parse_volume_scene
from clutter_gym.worlds.volume.spec import VolumeSpec

__all__ = [
    "ClutterArena",
    "ClutterSpec",
    "Obstacle",
    "ObstaclePool",
    "ReachScene",
    "Scene",
    "TableSpec",
    "TabletopArena",
    "VolumeArena",
    "VolumePathDistance",
    "VolumeScene",
    "VolumeSpec",
    "parse_scene",
    "parse_volume_scene",
    "sample_reach_scene",
    "sample_scene",
    "sample_volume_scene",
]
