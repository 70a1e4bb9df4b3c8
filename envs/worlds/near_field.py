"""Large scenes: only the static obstacles near the robot are bodies in the physics world.

Every body in a pybullet world costs each physics tick, however far away and asleep (docs/design-notes.md#large-scenes):
a scene of 10,000 static obstacles spent most of its step in the physics. A scene with at least
:data:`NEAR_FIELD_FROM` static obstacles therefore gives bodies only to those whose enclosing ball comes within an
*active ball* about the robot, found with a k-d tree over their centres. The env asks before every step
(:meth:`NearField.follow`) for a ball the robot cannot leave during it (its enclosing ball grown by twice its fastest
point's travel in one step); when that ball leaves the active one, the active ball is centred on it again,
:data:`MARGIN` wider, and the obstacles that came within it get bodies (pooled: ``worlds/pool.py``) while those
farther than one more margin give theirs back. Bodies that stay are not touched, so their contacts are kept.

What sees the whole scene still does: the collision checker's FCL objects hold every obstacle, and the Sim's
primitives hold each obstacle without a body as a backdrop row, which the exact LIDAR caster and the ray-cast camera
see. An env that reads pybullet's bodies otherwise (pybullet rays, pybullet's renderer: ``Sensor.needs_bodies``,
``render_mode``) keeps every obstacle a body. Movable obstacles always are bodies.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.transforms import yaw_quat
from clutter_gym.worlds.pool import ObstaclePool

#: static obstacles from which a scene keeps the far ones out of the physics world
NEAR_FIELD_FROM = 512
#: metres the active ball reaches beyond the ball the robot asked for; bodies are given back one margin farther
MARGIN = 0.5


class NearField:
    """Which static obstacles of the scene are bodies, following the robot (the module docstring).

    Args:
        pool: the pool that gives and parks bodies; its Sim's primitives get the backdrop.
    """

    def __init__(self, pool: ObstaclePool) -> None:
        self.pool = pool
        self._sim = pool.sim
        #: whether the far obstacles may leave the physics world (an env that reads bodies says no)
        self.allowed = True
        self._obstacles: tuple[Obstacle, ...] = ()
        self._static = np.zeros(0, dtype=int)  # scene indices of the static obstacles, the backdrop's rows
        self._tree: cKDTree | None = None
        self._enclosing = np.zeros(0)  # per static obstacle: the radius of its enclosing ball about its centre
        self._given: set[int] = set()  # the static rows whose obstacle has a body (the pool knows which)
        self._ball: tuple[np.ndarray, float] | None = None  # the active ball (centre, radius)
        self.refreshes = 0  # times the active ball moved (a figure for benchmarks and tests)

    @property
    def engaged(self) -> bool:
        """Whether this scene keeps far obstacles out of the physics world."""
        return self._tree is not None

    def place(self, obstacles: tuple[Obstacle, ...]) -> list[int]:
        """Put a new scene in: every obstacle a body (a small scene, or an env that reads bodies), or the movable ones
        only until :meth:`follow` says where the robot is; returns body ids in scene order, -1 for none."""
        self._obstacles, self._ball, self._given, self.refreshes = obstacles, None, set(), 0
        static = [i for i, o in enumerate(obstacles) if not o.movable]
        if not self.allowed or len(static) < NEAR_FIELD_FROM:
            self._tree = None
            self._sim.primitives.clear_backdrop()
            return self.pool.place(obstacles)
        self._static = np.array(static, dtype=int)
        chosen = [obstacles[i] for i in static]
        centres = np.array([o.centre for o in chosen], dtype=float)
        self._tree = cKDTree(centres)
        self._enclosing = 0.5 * np.linalg.norm(np.array([o.size for o in chosen], dtype=float), axis=1)
        halves = np.array([[0.5 * o.size[0], 0.5 * o.size[1], 0.5 * o.size[2]] for o in chosen])
        # the rotation a body's row gets (Sim.move_static), so that rays meet the same surfaces
        rotations = self._sim.obstacles.rotation_matrices([yaw_quat(o.yaw) for o in chosen])
        self._sim.primitives.set_backdrop([o.shape for o in chosen], centres, rotations, halves)
        self._sim.primitives.show_backdrop(np.ones(len(static), dtype=bool))
        return self.pool.place(obstacles, [i for i, o in enumerate(obstacles) if o.movable])

    def follow(self, centre: np.ndarray, radius: float) -> bool:
        """Make sure every static obstacle within ``radius`` metres of ``centre`` (its enclosing ball) is a body;
        returns whether bodies changed (then :meth:`bodies` says which there are)."""
        if self._tree is None:
            return False
        if self._ball is not None:
            held, reach = self._ball
            if float(np.linalg.norm(centre - held)) + radius <= reach:
                return False
        reach = radius + MARGIN
        self._ball = (np.array(centre, dtype=float), reach)
        self.refreshes += 1
        inside = set(self._within(centre, reach).tolist())
        keep = set(self._within(centre, reach + MARGIN).tolist())
        leave = sorted(self._given.difference(keep))
        enter = sorted(inside.difference(self._given))
        if not enter and not leave:
            return False
        static = self._static
        self.pool.update(self._obstacles, static[enter].tolist(), static[leave].tolist())
        self._given.difference_update(leave)
        self._given.update(enter)
        shown = np.ones(len(static), dtype=bool)
        shown[list(self._given)] = False
        self._sim.primitives.show_backdrop(shown)
        return True

    def _within(self, centre: np.ndarray, reach: float) -> np.ndarray:
        """Static rows whose obstacle's enclosing ball comes within ``reach`` of ``centre``."""
        assert self._tree is not None
        rows = np.array(self._tree.query_ball_point(centre, reach + float(self._enclosing.max())), dtype=int)
        gap = np.linalg.norm(self._tree.data[rows] - centre, axis=1) - self._enclosing[rows]
        return rows[gap <= reach]

    def bodies(self) -> list[int]:
        """The bodies of the scene's obstacles now (static and movable)."""
        return list(self.pool.placed.values())
