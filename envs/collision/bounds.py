"""Closed-form lower bounds on robot-shape-to-obstacle distances, vectorised over every pair.

Every robot shape lies inside a ball about its origin (``LinkShape.radius``), and every obstacle is a box or a
cylinder (upright, unless a movable one has been tipped over). The signed distance from the ball's centre to the
obstacle (negative inside: minus the depth to the nearest face), less the ball's radius, is a lower bound on the
shape's signed distance to the obstacle: on the separated side because the shape is inside the ball, and in
overlap because any motion that separates the ball separates the shape. One compiled pass per step
(:func:`~clutter_gym.collision.kernels.box_cylinder_distance`) gives all of them, so FCL is asked only about pairs
whose bound can still beat the best exact answer.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from clutter_gym.collision.kernels import box_cylinder_distance
from clutter_gym.datatypes import Obstacle

#: relative widening of the k-d tree's search radius in :meth:`ObstacleBounds.near`, so that the tree's own rounding
#: cannot leave out a column that the exact gap filter keeps
TREE_SLACK = 1e-9
#: obstacles whose enclosing radius is more than this many times the median one are left out of the k-d tree and
#: checked one by one: the tree's search must reach as far as its widest obstacle, and an arena's walls would widen
#: every search to half the arena
OUTSIZED = 2.0


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
        ordered = [obstacles[i] for i in self.index]
        centres = np.array([o.centre for o in ordered], dtype=float).reshape(-1, 3)
        yaw = np.array([o.yaw if o.shape != "cylinder" else 0.0 for o in ordered])
        cos, sin, zero, one = np.cos(yaw), np.sin(yaw), np.zeros(len(yaw)), np.ones(len(yaw))
        # world -> obstacle frame as one (4, 3 * n) matrix acting on homogeneous points: columns x..., y..., z...
        rotation_t = np.stack([np.stack([cos, sin, zero], -1), np.stack([-sin, cos, zero], -1),
                               np.stack([zero, zero, one], -1)], axis=1)  # (n, 3, 3): rows of R^T
        offset = -np.einsum("nij,nj->ni", rotation_t, centres)
        self._to_local = np.concatenate([rotation_t.transpose(2, 1, 0).reshape(3, -1), offset.T.reshape(1, -1)])
        half = 0.5 * np.array([o.size for o in ordered], dtype=float).reshape(-1, 3).T.copy()  # (3, n)
        self._split = len(boxes)
        self._radius = half[0, self._split:].copy()  # cylinders: the x half extent is the radius
        #: per column: the radius of the ball about the obstacle's centre that encloses it, and that centre
        self.enclosing = np.linalg.norm(half, axis=0)
        self.centres = centres
        # a cylinder is a box in (radial distance, nothing, z): an infinite y half extent takes its y out of play
        half[1, self._split:] = np.inf
        self._half = half
        self._column = np.argsort(self.index)  # obstacle index -> column
        #: k-d tree over the centres as they were when it was built (lazily: small scenes never ask for it), the
        #: columns it holds, and the widest enclosing radius among them
        self._tree: cKDTree | None = None
        self._tree_columns = np.zeros(0, dtype=int)
        self._widest = 0.0
        #: columns :meth:`near` checks one by one: outsized ones, and those moved since the tree was built (which
        #: the tree also holds, at their old centres: ``_moved`` marks them)
        self._each = np.zeros(0, dtype=int)
        self._moved = np.zeros(len(self.index), dtype=bool)

    def move(self, obstacles: np.ndarray, centres: np.ndarray, rotations: np.ndarray) -> None:
        """Put ``obstacles`` (indices) at ``centres`` (k, 3) with ``rotations`` (k, 3, 3), world frame: any
        orientation, for movable obstacles that the physics has pushed or tipped over."""
        columns = self._column[obstacles]
        to_local = self._to_local.reshape(4, 3, len(self.index))  # [j, i, column]: R[j, i], then -R^T centre
        to_local[:3, :, columns] = rotations.transpose(1, 2, 0)
        to_local[3, :, columns] = -np.einsum("kji,kj->ki", rotations, centres)
        self.centres[columns] = centres
        if self._tree is not None:  # the tree holds their old centres: :meth:`near` checks them one by one
            self._each = np.union1d(self._each, columns)
            self._moved[columns] = True

    def __len__(self) -> int:
        return len(self.index)

    def near(self, centre: np.ndarray, reach: float) -> np.ndarray:
        """Columns whose obstacle's enclosing ball comes within ``reach`` of ``centre`` (3,), ascending.

        A k-d tree over the centres, built on the first call, gives the columns whose centres lie within ``reach``
        plus the widest enclosing radius among its own; outsized obstacles (``OUTSIZED``) and movable ones moved
        since then (the tree has their old centres) are added whatever their distance. Each of those is then kept
        by the same gap test as a pass over every column would make, so the answer is that pass's, at a cost that
        follows the obstacles near ``centre``.
        """
        if self._tree is None:
            self._build_tree()
        assert self._tree is not None
        radius = (reach + self._widest) * (1.0 + TREE_SLACK)
        hits = self._tree.query_ball_point(centre, radius) if radius >= 0.0 else []
        columns = self._tree_columns[np.array(hits, dtype=int)]
        if self._each.size:
            columns = np.concatenate((columns[~self._moved[columns]], self._each))
        columns.sort()
        offset = self.centres[columns] - centre
        gap = np.sqrt(np.add.reduce(offset * offset, axis=1)) - self.enclosing[columns]  # np.linalg.norm's sum
        return columns[gap <= reach]

    def _build_tree(self) -> None:
        """The k-d tree of :meth:`near` over the columns not outsized, at their centres now."""
        typical = float(np.median(self.enclosing)) if len(self.index) else 0.0
        outsized = self.enclosing > OUTSIZED * typical
        self._tree_columns = np.flatnonzero(~outsized)
        self._tree = cKDTree(self.centres[self._tree_columns])  # a copy: move() writes into the centres
        self._widest = float(self.enclosing[self._tree_columns].max(initial=0.0))
        self._each = np.flatnonzero(outsized)
        self._moved[:] = False

    def signed_distance_to(self, points: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
        """(P, len(obstacles)) :meth:`signed_distance` from each point to the obstacles with these indices, in their
        order."""
        columns = self._column[obstacles]
        order = np.argsort(columns)
        out = np.empty((len(points), len(obstacles)))
        out[:, order] = self.signed_distance(points, columns[order])
        return out

    def signed_distance(self, points: np.ndarray, columns: np.ndarray | None = None) -> np.ndarray:
        """(P, columns) signed distance from each point (P, 3) to each obstacle, exact for boxes and cylinders.

        Positive outside, minus the distance to the nearest face inside. ``columns`` (ascending) selects some.
        """
        n = len(self.index)
        to_local, half, split, radius = self._to_local, self._half, self._split, self._radius
        if columns is not None:
            split = int(np.searchsorted(columns, self._split))
            to_local = np.ascontiguousarray(to_local.reshape(4, 3, n)[:, :, columns].reshape(4, -1))
            half, radius = np.ascontiguousarray(half[:, columns]), self._radius[columns[split:] - self._split]
        return box_cylinder_distance(np.ascontiguousarray(points, dtype=float), to_local, half, split, radius)
