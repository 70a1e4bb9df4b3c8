"""What every world's arena shares: its fixed structure and pooled clutter in an :class:`ObstaclePool` (only the
near part of a large scene: :class:`NearField`), and each episode's scene taken from ``options["scene"]`` or drawn.
A world's arena adds how it builds its structure (``load``), parses and draws its scenes, and frames its
``rgb_array`` view."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Generic, TypeVar

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.interfaces import Layout
from clutter_gym.worlds.near_field import NearField
from clutter_gym.worlds.parsing import scene_from_options
from clutter_gym.worlds.pool import ObstaclePool

S = TypeVar("S", bound=Layout)  # the world's scene type


class PooledArena(Generic[S]):
    """An arena whose clutter is pooled bodies moved into place each episode; ``load`` makes :attr:`_pool`."""

    _pool: ObstaclePool | None = None
    _near: NearField | None = None
    #: whether a large scene may keep its far static obstacles out of the physics world (the env says no when
    #: something reads every body: pybullet's rays or renderer)
    near_field = True

    @property
    def pool_size(self) -> int:
        """Obstacle bodies in the world (placed and parked)."""
        return self._pool.size

    def choose_scene(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> S:
        """The user's scene from ``options["scene"]`` if given, else a layout drawn from ``rng``.

        Raises:
            ValueError: unknown option keys or a malformed scene (the message names the field).
        """
        return scene_from_options(options, parse=self._parse, sample=lambda: self._sample(rng))

    def place(self, scene: S) -> tuple[tuple[Obstacle, ...], list[int]]:
        """Move pooled bodies into ``scene``; returns every obstacle (the fixed structure included) and its body
        ids, in the same order."""
        if self._near is None or self._near.pool is not self._pool:  # load made a new pool
            self._near = NearField(self._pool)
        self._near.allowed = self.near_field
        bodies = self._near.place(scene.obstacles)
        return scene.obstacles + self._pool.fixed, bodies + self._pool.fixed_bodies

    @property
    def near_field_engaged(self) -> bool:
        """Whether this episode's scene keeps its far static obstacles out of the physics world."""
        return self._near is not None and self._near.engaged

    def follow(self, centre: np.ndarray, radius: float) -> list[int] | None:
        """Give bodies to the static obstacles within ``radius`` metres of ``centre`` (:meth:`NearField.follow`);
        returns the bodies of the obstacles and fixed structure when they changed, else None."""
        if self._near is None or not self._near.follow(centre, radius):
            return None
        return self._near.bodies() + self._pool.fixed_bodies

    def _parse(self, raw: Any) -> S:
        """A user's scene, checked (errors name the field)."""
        raise NotImplementedError

    def _sample(self, rng: np.random.Generator) -> S:
        """A scene drawn from ``rng``."""
        raise NotImplementedError
