"""Robot-vs-scene clearance and contacts with FCL, cross-checked against pybullet's own contact points.

The obstacle broad phase (a dynamic AABB tree) is rebuilt on reset only; each step moves the robot's link
objects (one transform per collision element, from the batched link states the robot already read) and runs one
manager-vs-manager distance query. The contact enumeration runs only when the clearance says there is contact.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import fcl
import numpy as np

from clutter_gym.collision.urdf_geometry import CollisionElement
from clutter_gym.robots.state import RobotState
from clutter_gym.transforms import quat_to_matrix
from clutter_gym.worlds.scene import Obstacle

#: Clearance reported when there is nothing to measure against (an empty scene without walls), metres.
NO_OBSTACLE_CLEARANCE = 1e3


@dataclass(frozen=True, slots=True)
class CollisionReport:
    """What the two engines say about the robot and the scene after a step.

    Attributes:
        min_clearance: signed FCL distance from the robot to the nearest obstacle or wall, metres; negative is
            penetration depth.
        n_contacts: FCL robot-link/obstacle pairs closer than the contact tolerance.
        pybullet_contacts: pybullet contact points between the robot and obstacles within the tolerance.
        disagreement: exactly one of the two engines reports contact.
    """

    min_clearance: float
    n_contacts: int
    pybullet_contacts: int
    disagreement: bool

    @property
    def in_contact(self) -> bool:
        return self.n_contacts > 0


def obstacle_geometry(o: Obstacle) -> fcl.CollisionObject:
    """FCL object for an obstacle standing on the floor."""
    if o.shape == "cylinder":
        geom = fcl.Cylinder(o.radius, o.size[2])
    else:
        geom = fcl.Box(*o.size)
    half = 0.5 * o.yaw
    q_wxyz = np.array([np.cos(half), 0.0, 0.0, np.sin(half)])
    return fcl.CollisionObject(geom, fcl.Transform(q_wxyz, [o.position[0], o.position[1], 0.5 * o.size[2]]))


class CollisionChecker:
    """FCL model of one robot and the current scene.

    Args:
        elements: the robot's collision primitives (see :func:`load_collision_elements`).
        base_link: name of the URDF base link (its pose is ``RobotState.position``/``rotation``).
        contact_tolerance: distance at or below which either engine counts a contact, metres.
    """

    def __init__(self, elements: Sequence[CollisionElement], base_link: str, contact_tolerance: float = 1e-3) -> None:
        self._elements = list(elements)
        self._base_link = base_link
        self.contact_tolerance = contact_tolerance
        self._robot_objects = [fcl.CollisionObject(e.geometry, fcl.Transform()) for e in self._elements]
        self._robot_manager = fcl.DynamicAABBTreeCollisionManager()
        self._robot_manager.registerObjects(self._robot_objects)
        self._robot_manager.setup()
        self._local_pos = np.array([e.position for e in self._elements])
        self._local_rot = quat_to_matrix(np.array([e.quaternion for e in self._elements]))
        self._obstacle_manager: fcl.DynamicAABBTreeCollisionManager | None = None
        self._obstacle_objects: list[fcl.CollisionObject] = []
        self._obstacle_bodies: frozenset[int] = frozenset()
        # GJK's error against the closed form is <= 2e-5 m within 0.5 m and <= 4e-5 m within 1 m, but reaches
        # 7 mm for obstacles over a metre away, with either of FCL's solvers (benchmarks/fcl_accuracy.py). Contact
        # and the clearance penalty only look below 0.1 m.
        self._request = fcl.DistanceRequest(enable_signed_distance=True)
        self._rows: np.ndarray | None = None

    def set_scene(self, obstacles: Sequence[Obstacle], bodies: Sequence[int]) -> None:
        """Rebuild the obstacle broad phase (call on reset). ``bodies`` are the matching pybullet body ids."""
        self._obstacle_objects = [obstacle_geometry(o) for o in obstacles]
        self._obstacle_bodies = frozenset(bodies)
        manager = fcl.DynamicAABBTreeCollisionManager()
        if self._obstacle_objects:
            manager.registerObjects(self._obstacle_objects)
        manager.setup()
        self._obstacle_manager = manager

    def _sync(self, state: RobotState) -> None:
        """Move every robot collision object to its link's pose in ``state``."""
        if self._rows is None:  # element -> row of [base, *state.links]; fixed for a robot
            names = (self._base_link, *state.link_names)
            self._rows = np.array([names.index(e.link) for e in self._elements])
        rot = np.concatenate((state.rotation[None], state.links.rotation))[self._rows]
        pos = np.concatenate((state.position[None], state.links.position))[self._rows]
        world_rot = rot @ self._local_rot
        world_pos = pos + (rot @ self._local_pos[:, :, None])[:, :, 0]
        for obj, r, t in zip(self._robot_objects, world_rot, world_pos):
            obj.setRotation(r)
            obj.setTranslation(t)
        self._robot_manager.update()

    def min_clearance(self, state: RobotState) -> float:
        """Signed distance from the robot to the nearest obstacle, metres (FCL)."""
        self._sync(state)
        if not self._obstacle_objects:
            return NO_OBSTACLE_CLEARANCE
        data = fcl.DistanceData(request=self._request)
        self._robot_manager.distance(self._obstacle_manager, data, fcl.defaultDistanceCallback)
        return float(data.result.min_distance)

    def _count_contacts(self) -> int:
        """Robot-link/obstacle pairs within the contact tolerance (robot objects already synced)."""
        tol, request, hits = self.contact_tolerance, self._request, []

        def within(o1: fcl.CollisionObject, o2: fcl.CollisionObject, _data: object) -> tuple[bool, float]:
            # Returning ``tol`` as the running bound makes the tree visit every pair closer than ``tol``.
            if fcl.distance(o1, o2, request, fcl.DistanceResult()) <= tol:
                hits.append(1)
            return False, tol

        self._robot_manager.distance(self._obstacle_manager, None, within)
        return len(hits)

    def check(self, state: RobotState, pybullet_contacts: Sequence[tuple[int, float]]) -> CollisionReport:
        """Clearance and contacts of the robot in ``state``.

        Args:
            state: the robot state after the step.
            pybullet_contacts: (other body id, contact distance) of the robot's pybullet contact points.
        """
        clearance = self.min_clearance(state)
        tol = self.contact_tolerance
        # at least one pair when the clearance says contact, even if a pairwise query lands a hair above tol
        n_fcl = max(1, self._count_contacts()) if clearance <= tol else 0
        n_pb = sum(1 for body, d in pybullet_contacts if d <= tol and body in self._obstacle_bodies)
        return CollisionReport(clearance, n_fcl, n_pb, (n_fcl > 0) != (n_pb > 0))
