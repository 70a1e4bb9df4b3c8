"""A planned joint-space path as the ClutterReach task walks it: by arc length, forward only.

It imports no engine (no FCL, no pybullet), so the task that walks a path loads none; the planner that makes one
is :mod:`clutter_gym.planning.joint_space`.
"""

from __future__ import annotations

import numpy as np

#: Largest joint change between two configurations the planner checks along an edge, and between two points of a
#: walked :class:`JointPath`, radians.
RESOLUTION = 0.03


class JointPath:
    """A joint-space path walked by arc length: how far along it a configuration is, and the point ahead.

    Args:
        path: (k, n_joints) configurations, k >= 1.
    """

    def __init__(self, path: np.ndarray) -> None:
        path = np.atleast_2d(np.asarray(path, dtype=float))
        points = [path[:1]]
        for a, b in zip(path[:-1], path[1:]):
            n = max(1, int(np.ceil(np.linalg.norm(b - a) / RESOLUTION)))
            points.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
        self.points = np.concatenate(points)
        self.arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self.points, axis=0), axis=1))])
        self.index = 0

    @property
    def length(self) -> float:
        """Arc length of the path, radians (Euclidean in joint space)."""
        return float(self.arc[-1])

    def advance(self, q: np.ndarray, window: float) -> None:
        """Move the path index to the point nearest ``q`` among those up to ``window`` radians of arc ahead;
        the index never moves back, so a configuration that strays does not restart the path."""
        ahead = np.searchsorted(self.arc, self.arc[self.index] + window, side="right")
        d = np.linalg.norm(self.points[self.index:ahead] - q, axis=1)
        self.index += int(np.argmin(d))

    def waypoint(self, lookahead: float) -> np.ndarray:
        """The path point ``lookahead`` radians of arc beyond the current index (the end if that is beyond)."""
        i = np.searchsorted(self.arc, self.arc[self.index] + lookahead, side="left")
        return self.points[min(i, len(self.points) - 1)]
