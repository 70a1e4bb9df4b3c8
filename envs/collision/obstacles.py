"""FCL objects for a scene's obstacles (upright boxes and cylinders), reused from scene to scene."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

import fcl
import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.transforms import quat_to_matrix, yaw_quat

#: obstacle FCL objects kept for reuse; past this many the cache starts again (see :class:`ObstacleObjects`)
MAX_CACHED_OBJECTS = 4096


def obstacle_shape(o: Obstacle) -> fcl.CollisionGeometry:
    """FCL shape of an obstacle in its own frame (centred, cylinder along z)."""
    return fcl.Cylinder(o.radius, o.size[2]) if o.shape == "cylinder" else fcl.Box(*o.size)


def obstacle_transform(o: Obstacle) -> fcl.Transform:
    """The pose of an obstacle's FCL object (its bottom face at height ``o.z``)."""
    # a rotation matrix, not a quaternion: FCL's are (w, x, y, z), ours (x, y, z, w); bit for bit the matrix FCL
    # would build from the quaternion
    return fcl.Transform(quat_to_matrix(np.array(yaw_quat(o.yaw))), list(o.centre))


def obstacle_object(o: Obstacle) -> fcl.CollisionObject:
    """A new FCL object for an obstacle (an env reuses them instead: :class:`ObstacleObjects`)."""
    return fcl.CollisionObject(obstacle_shape(o), obstacle_transform(o))


class ObstacleObjects:
    """FCL objects for the obstacles of each scene, reused across scenes like the pybullet bodies of the pool.

    python-fcl loses part of every ``CollisionObject`` it frees (its deallocator ``free``s the C++ object without
    running its destructor), so building a scene's objects anew on every reset grows memory without end
    (docs/design-notes.md#memory). Objects are kept per exact shape and moved into place; past
    :data:`MAX_CACHED_OBJECTS` (user scenes of ever new sizes) the cache starts again, leaving that loss behind.
    """

    def __init__(self) -> None:
        self._kept: dict[tuple, list[fcl.CollisionObject]] = defaultdict(list)
        self._count = 0

    def place(self, obstacles: Sequence[Obstacle]) -> list[fcl.CollisionObject]:
        """One object per obstacle, in order, each at its obstacle's pose."""
        if self._count > MAX_CACHED_OBJECTS:
            self._kept.clear()
            self._count = 0
        used: dict[tuple, int] = defaultdict(int)
        objects = []
        for o in obstacles:
            key = (o.shape, o.size)
            kept, i = self._kept[key], used[key]
            used[key] += 1
            if i == len(kept):
                kept.append(fcl.CollisionObject(obstacle_shape(o), fcl.Transform()))
                self._count += 1
            kept[i].setTransform(obstacle_transform(o))
            objects.append(kept[i])
        return objects
