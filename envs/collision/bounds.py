"""Closed-form lower bounds on robot-shape-to-obstacle distances, vectorised over every pair.

Every robot shape lies inside a ball about its origin (``LinkShape.radius``), and every obstacle is an upright
box or cylinder. The signed distance from the ball's centre to the obstacle (negative inside: minus the depth to
the nearest face), less the ball's radius, is a lower bound on the shape's signed distance to the obstacle: on
the separated side because the shape is inside the ball, and in overlap because any motion that separates the
ball separates the shape. One numpy pass per step gives all of them, so FCL is asked only about pairs whose
bound can still beat the best exact answer.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clutter_gym.worlds.scene import Obstacle


def _signed(qx: np.ndarray, qy: np.ndarray, qz: np.ndarray | None = None) -> np.ndarray:
    """Signed distance from per-axis excesses ``|local| - half`` (2 or 3 axes)."""
    ox, oy = np.maximum(qx, 0.0), np.maximum(qy, 0.0)
    inside = np.maximum(qx, qy)
    if qz is None:
        outside = np.hypot(ox, oy)
    else:
        oz = np.maximum(qz, 0.0)
        outside = np.sqrt(ox * ox + oy * oy + oz * oz)
        np.maximum(inside, qz, out=inside)
    return outside + np.minimum(inside, 0.0, out=inside)


class ObstacleBounds:
    """The obstacles of one scene as arrays, for vectorised point distances.

    Boxes and cylinders are kept apart (each has its own closed form), so the columns of
    :meth:`signed_distance` come in the order of :attr:`index`: the boxes, then the cylinders.

    Args:
        obstacles: upright boxes (any yaw) and cylinders.
    """

    def __init__(self, obstacles: Sequence[Obstacle]) -> None:
        boxes = [i for i, o in enumerate(obstacles) if o.shape != "cylinder"]
        cylinders = [i for i, o in enumerate(obstacles) if o.shape == "cylinder"]
        #: obstacle index of every column
        self.index = np.array(boxes + cylinders, dtype=int)
        centres = np.array([o.centre for o in obstacles], dtype=float).reshape(-1, 3)
        half = 0.5 * np.array([o.size for o in obstacles], dtype=float).reshape(-1, 3)
        yaw = np.array([o.yaw for o in obstacles], dtype=float)
        self._box = (*centres[boxes].T, np.cos(yaw[boxes]), np.sin(yaw[boxes]), *half[boxes].T)
        self._cylinder = (*centres[cylinders].T, half[cylinders, 0], half[cylinders, 2])
        self._split = len(boxes)
        #: per column: the radius of the ball about the obstacle's centre that encloses it, and that centre
        self.enclosing = np.linalg.norm(half[self.index], axis=1)
        self.centres = centres[self.index]

    def __len__(self) -> int:
        return len(self.index)

    def near(self, centre: np.ndarray, reach: float) -> np.ndarray:
        """Columns whose obstacle's enclosing ball comes within ``reach`` of ``centre`` (3,), ascending."""
        gap = np.linalg.norm(self.centres - centre, axis=1) - self.enclosing
        return np.flatnonzero(gap <= reach)

    def signed_distance(self, points: np.ndarray, columns: np.ndarray | None = None) -> np.ndarray:
        """(P, columns) signed distance from each point (P, 3) to each obstacle, exact for boxes and cylinders.

        Positive outside, minus the distance to the nearest face inside. ``columns`` (ascending) selects some.
        """
        box, cylinder, split = self._box, self._cylinder, self._split
        if columns is not None:
            split = int(np.searchsorted(columns, self._split))
            box = tuple(a[columns[:split]] for a in box)
            cylinder = tuple(a[columns[split:] - self._split] for a in cylinder)
        x, y, z = points[:, 0:1], points[:, 1:2], points[:, 2:3]
        out = np.empty((len(points), len(box[0]) + len(cylinder[0])))
        if split:
            cx, cy, cz, cos, sin, hx, hy, hz = box
            dx, dy = x - cx, y - cy
            qx = np.abs(dx * cos + dy * sin) - hx
            qy = np.abs(dy * cos - dx * sin) - hy
            out[:, :split] = _signed(qx, qy, np.abs(z - cz) - hz)
        if split < out.shape[1]:
            cx, cy, cz, radius, hz = cylinder
            out[:, split:] = _signed(np.hypot(x - cx, y - cy) - radius, np.abs(z - cz) - hz)
        return out
