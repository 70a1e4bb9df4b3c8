"""The table world in the Sim: the table (built once) and the pooled clutter on it."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from clutter_gym.sim import Sim
from clutter_gym.worlds.pool import ObstaclePool
from clutter_gym.worlds.pooled_arena import PooledArena
from clutter_gym.worlds.table.sample import sample_reach_scene
from clutter_gym.worlds.table.scene import ReachScene, parse_reach_scene
from clutter_gym.worlds.table.spec import TABLE, TableSpec

#: The rgb_array view (:meth:`TabletopArena.render_camera`), world frame, metres.
VIEW_EYE, VIEW_TARGET = (1.1, -0.8, 0.8), (0.3, 0.0, 0.3)


class TabletopArena(PooledArena[ReachScene]):
    """The table (built once) and the pooled clutter of one env.

    Args:
        spec: layout parameters.
        ready: the arm's ready joint positions (start poses are drawn around it; a user scene without a start
            gets it exactly).
        lower, upper: joint limits, for validating user start poses.
        shoulder, reach: targets are drawn (and user targets accepted) within ``reach`` metres of ``shoulder``.
    """

    def __init__(self, spec: TableSpec, ready: Sequence[float], lower: np.ndarray, upper: np.ndarray,
                 shoulder: np.ndarray | Sequence[float], reach: float) -> None:
        self.spec = spec
        self.ready = tuple(ready)
        self._lower, self._upper = lower, upper
        self._shoulder, self._reach = tuple(float(v) for v in shoulder), float(reach)

    def load(self, sim: Sim) -> None:
        """Create the table (once per env)."""
        self._pool = ObstaclePool(sim, (TABLE,))

    def _sample(self, rng: np.random.Generator) -> ReachScene:
        return sample_reach_scene(rng, self.spec, self.ready, self._shoulder, self._reach)

    def _parse(self, raw: Any) -> ReachScene:
        """A user scene; one without a start begins at the ready pose."""
        scene = parse_reach_scene(raw, len(self.ready), self._lower, self._upper, self._shoulder, self._reach)
        return scene if scene.start is not None else ReachScene(scene.obstacles, self.ready, scene.target)

    def render_camera(self, sim: Sim, robot: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eye, target) of the rgb_array view: a fixed view of the arm's workspace from the front right, near
        enough for the hand and the target to read, with the arm's usual poses in frame (both are ringed, also when
        the shelf or the arm hides them). It casts no rays."""
        return np.array(VIEW_EYE), np.array(VIEW_TARGET)
