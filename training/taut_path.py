"""ClutterFly-v1's ``taut`` teacher: the planned path pulled taut, so that its label does not depend on where in a
grid cell the drone is.

The planner teacher's waypoint is the point ``subgoal_lookahead`` along the path behind the progress field. That
path runs from the drone to the centre of a grid cell near it, then from cell centre to cell centre (moves in a
few fixed directions), so its first half metre turns by up to tens of degrees as the drone moves a few centimetres
inside a cell: the same LIDAR scan is labelled with different directions, and a student cannot tell
which. The taut teacher looks along the same path for the farthest of its points (up to :data:`REACH` metres along
it) that the drone sees in a straight line with :data:`MARGIN` to spare beyond its radius, and points at that:
the corner of the obstacle the path rounds, or the goal. Which way round an obstacle the path goes is still the
map's; how the drone heads there is now a function of where the obstacles are.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from clutter_gym.training.teachers import PlannerFlyer
from clutter_gym.worlds.volume.grid import signed_distance

#: metres along the planned path the teacher looks for a point in sight
REACH = 2.0
#: metres beyond the robot's radius that a straight line to that point keeps from every obstacle and face
MARGIN = 0.05
#: metres between the points of a line that are checked
SAMPLE = 0.05


def taut_point(path: np.ndarray, clearance: Callable[[np.ndarray], np.ndarray], reach: float = REACH) -> np.ndarray:
    """The farthest point of ``path`` ((k, 3): the drone's position, then the path's points), up to ``reach``
    metres along it, whose straight line from the first point keeps ``clearance`` (points (n, 3) -> metres) above 0
    at every :data:`SAMPLE`; the path's second point when none does."""
    start = path[0]
    lengths = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    last = int(np.searchsorted(lengths, reach, side="right"))  # path[:last] lie within reach
    candidates = list(path[1:last])
    if last < len(path):  # the point at exactly ``reach`` along the path, between two of its points
        t = (reach - lengths[last - 1]) / max(lengths[last] - lengths[last - 1], 1e-12)
        candidates.append(path[last - 1] + t * (path[last] - path[last - 1]))
    if not candidates:
        return path[-1]
    ends = np.array(candidates)
    counts = np.maximum(np.ceil(np.linalg.norm(ends - start, axis=1) / SAMPLE).astype(int), 1)
    owner = np.repeat(np.arange(len(ends)), counts)
    fraction = (np.concatenate([np.arange(1, c + 1) for c in counts]) / np.repeat(counts, counts))[:, None]
    clear = np.ones(len(ends), dtype=bool)
    np.logical_and.at(clear, owner, clearance(start + fraction * (ends[owner] - start)) > 0.0)
    blocked = np.flatnonzero(~clear)
    visible = len(ends) if len(blocked) == 0 else int(blocked[0])
    return ends[visible - 1] if visible else path[1]


class TautFlyer(PlannerFlyer):
    """The planner teacher pointing at :func:`taut_point` of its path (see the module docstring)."""

    def __init__(self, env: gym.Env, waypoint: bool = False) -> None:
        super().__init__(env, waypoint)
        self.env = env.unwrapped

    def _clearance(self, points: np.ndarray) -> np.ndarray:
        """Metres from each point to the nearest obstacle or face of the volume, less the radius and margin."""
        env = self.env
        x, y, z = points.T
        sx, sy, sz = env.task.spec.size
        gap = np.minimum(np.minimum(0.5 * sx - np.abs(x), 0.5 * sy - np.abs(y)), np.minimum(z, sz - z))
        for obstacle in env.scene.obstacles:
            gap = np.minimum(gap, signed_distance(obstacle, x, y, z))
        return gap - env.task.robot_radius - MARGIN

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        state = self.env.robot_state()
        position = np.asarray(state.position, dtype=float)
        point = taut_point(self.env.task.planned_path(position), self._clearance)
        offset = state.rotation.T @ (point - position)
        length = float(np.linalg.norm(offset))
        lookahead = float(self.env.task.subgoal_lookahead)
        subgoal = offset * (lookahead / length) if length > lookahead else offset  # its direction, as the planner's
        return super().__call__({**obs, "subgoal": subgoal.astype(np.float32)}, info)

