"""The table world in the Sim: the table (built once) and the pooled clutter on it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.sim import Sim
from clutter_gym.worlds.parsing import scene_from_options
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.table.sample import sample_reach_scene
from clutter_gym.worlds.table.scene import ReachScene, parse_reach_scene
from clutter_gym.worlds.table.spec import REACH_RADIUS, SHOULDER, TABLE, TableSpec

#: The rgb_array view (:meth:`TabletopArena.render_camera`), world frame, metres.
VIEW_EYE, VIEW_TARGET = (1.1, -0.8, 0.8), (0.3, 0.0, 0.3)


class TabletopArena:
    """The table (built once) and the pooled clutter of one env.

    Args:
        spec: layout parameters.
        ready: the arm's ready joint positions (start poses are drawn around it; a user scene without a start
            gets it exactly).
        lower, upper: joint limits, for validating user start poses.
        shoulder, reach: targets are drawn (and user targets accepted) within ``reach`` metres of ``shoulder``.
    """

    def __init__(self, spec: TableSpec, ready: Sequence[float], lower: np.ndarray, upper: np.ndarray,
                 shoulder: np.ndarray | Sequence[float] = SHOULDER, reach: float = REACH_RADIUS) -> None:
        self.spec = spec
        self.ready = tuple(ready)
        self._lower, self._upper = lower, upper
        self._shoulder, self._reach = tuple(float(v) for v in shoulder), float(reach)
        self._pool: ObstaclePool | None = None

    def load(self, sim: Sim) -> None:
        """Create the table (once per env)."""
        self._pool = ObstaclePool(sim, (TABLE,))

    @property
    def pool_size(self) -> int:
        return self._pool.size

    def choose_scene(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> ReachScene:
        """The user's scene from ``options["scene"]`` if given, else a seeded random layout.

        Raises:
            ValueError: unknown option keys or a malformed scene (the message names the field).
        """
        return scene_from_options(
            options, parse=self._parse,
            sample=lambda: sample_reach_scene(rng, self.spec, self.ready, self._shoulder, self._reach)
        )

    def _parse(self, spec: Any) -> ReachScene:
        """A user scene; one without a start begins at the ready pose."""
        scene = parse_reach_scene(spec, len(self.ready), self._lower, self._upper, self._shoulder, self._reach)
        return scene if scene.start is not None else ReachScene(scene.obstacles, self.ready, scene.target)

    def place(self, scene: ReachScene) -> tuple[tuple[Obstacle, ...], list[int]]:
        """Move pooled bodies into ``scene``; returns every obstacle (the table included) and its body ids."""
        bodies = self._pool.place(scene.obstacles)
        return scene.obstacles + self._pool.fixed, bodies + self._pool.fixed_bodies

    def render_camera(self, sim: Sim, robot: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eye, target) of the rgb_array view: a fixed view of the arm's workspace from the front right, near
        enough for the hand and the target to read, with the arm's usual poses in frame (both are ringed, also when
        the shelf or the arm hides them). It casts no rays."""
        return np.array(VIEW_EYE), np.array(VIEW_TARGET)
