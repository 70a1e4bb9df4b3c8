"""Finer shapes of a robot's links that settle a coarse level's self-collision hits, moved only when asked.

A coarse level's shapes (``sphere``, ``primitive``) enclose the ``convex`` level's, and around a joint they overlap
in most poses where the links themselves are apart. Used as a broad phase, they still rule out every pair they do
not find touching; :class:`PairConfirmer` answers the pairs they do find touching with the finer shapes, so the
verdict is the finer level's while a step in which no coarse pair touches costs what the coarse level costs.
"""

from __future__ import annotations

from collections.abc import Sequence

import fcl
import numpy as np

from clutter_gym.collision.fidelity import LinkShape


class PairConfirmer:
    """The finer shapes of every link, placed at the link poses of the last :meth:`set_link_poses` when a pair
    of links is asked about.

    Args:
        shapes: the finer level's shapes (``convex``'s).
        link_names: names of the rows of the pose arrays given to :meth:`set_link_poses`.
    """

    def __init__(self, shapes: Sequence[LinkShape], link_names: Sequence[str]) -> None:
        self.shapes = list(shapes)
        self._rows = [list(link_names).index(s.link) for s in self.shapes]
        self._objects = [fcl.CollisionObject(s.geometry, fcl.Transform()) for s in self.shapes]
        #: per shape: placed at its link's origin, unrotated (most mesh elements), so its pose is the link's
        self._at_origin = [not s.position.any() and np.array_equal(s.rotation, np.eye(3)) for s in self.shapes]
        self._by_link: dict[str, list[int]] = {}
        for i, s in enumerate(self.shapes):
            self._by_link.setdefault(s.link, []).append(i)
        self._request = fcl.CollisionRequest()
        self._poses: tuple[np.ndarray, np.ndarray] | None = None
        self._placed = [False] * len(self.shapes)

    def set_link_poses(self, positions: np.ndarray, rotations: np.ndarray) -> None:
        """Link positions (L, 3) and rotations (L, 3, 3) by row, copied; no shape is moved until asked for."""
        self._poses = (np.array(positions, dtype=float), np.array(rotations, dtype=float))
        self._placed = [False] * len(self.shapes)

    def collide(self, a: str, b: str) -> bool:
        """Whether links ``a`` and ``b`` touch at the last link poses."""
        if self._poses is None:
            raise RuntimeError("set_link_poses() before collide()")
        for i in self._by_link.get(a, ()):
            for j in self._by_link.get(b, ()):
                if self._touch(self._place(i), self._place(j)):
                    return True
        return False

    def _touch(self, i: int, j: int) -> bool:
        return fcl.collide(self._objects[i], self._objects[j], self._request, fcl.CollisionResult()) > 0

    def _place(self, i: int) -> int:
        """Move shape ``i`` to its link's pose once per :meth:`set_link_poses`; returns ``i``."""
        if not self._placed[i]:
            positions, rotations = self._poses
            row, obj = self._rows[i], self._objects[i]
            if self._at_origin[i]:
                obj.setRotation(rotations[row])
                obj.setTranslation(positions[row])
            else:
                shape = self.shapes[i]
                obj.setRotation(rotations[row] @ shape.rotation)
                obj.setTranslation(positions[row] + rotations[row] @ shape.position)
            self._placed[i] = True
        return i
