"""Worlds: scenes as plain data, seeded layouts with a reachability guarantee, the path distance to the goal, and
the body pool that puts a scene into a Sim. One subpackage per world, with one file per role: ``floor``
(ClutterNav-v1), ``table`` (ClutterReach-v1) and ``volume`` (ClutterFly-v1); the parts they share sit here.

The names below are imported on first use (PEP 562 ``__getattr__``), so that importing one world's data (a task
importing its scene type) loads neither the other worlds nor, through the arenas, the simulator.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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

#: Each public name and the module it is imported from.
_HOMES = {
    "Obstacle": "clutter_gym.datatypes",
    "ClutterArena": "clutter_gym.worlds.floor.arena",
    "sample_scene": "clutter_gym.worlds.floor.sample",
    "Scene": "clutter_gym.worlds.floor.scene",
    "parse_scene": "clutter_gym.worlds.floor.scene",
    "ClutterSpec": "clutter_gym.worlds.floor.spec",
    "ObstaclePool": "clutter_gym.worlds.pool",
    "TabletopArena": "clutter_gym.worlds.table.arena",
    "sample_reach_scene": "clutter_gym.worlds.table.sample",
    "ReachScene": "clutter_gym.worlds.table.scene",
    "TableSpec": "clutter_gym.worlds.table.spec",
    "VolumeArena": "clutter_gym.worlds.volume.arena",
    "VolumePathDistance": "clutter_gym.worlds.volume.path",
    "sample_volume_scene": "clutter_gym.worlds.volume.sample",
    "VolumeScene": "clutter_gym.worlds.volume.scene",
    "parse_volume_scene": "clutter_gym.worlds.volume.scene",
    "VolumeSpec": "clutter_gym.worlds.volume.spec",
}

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


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_HOMES[name]), name)
    globals()[name] = value  # later lookups find it without this call
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
