"""Robot-vs-scene clearance, contacts, self-collision and swept checks with FCL, cross-checked against pybullet.

The obstacle broad phase (a dynamic AABB tree) is rebuilt on reset only. Each step moves the robot's FCL
objects to the link poses the robot read in one batched call, then:

1. one query per robot shape against the obstacle tree gives every link's clearance (capped at
   ``clearance_range``), its witness points and the closest obstacle;
2. pairs within ``contact_tolerance`` are enumerated as contacts with their penetration depth;
3. enabled self pairs (the ACM) are tested, after a bounding-ball filter;
4. shapes that moved faster than ``swept_speed`` are swept from their previous pose (``fcl.continuousCollide``,
   translation motion, conservative advancement) against the obstacles near their path: a hit the end-of-step
   check does not see is *tunneling*. The translation motion holds the start rotation (measured: it ignores
   rotation), so a step's rotation is covered only at its two ends; mesh shapes sweep their convex hull
   (conservative advancement never detects a moving BVH).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import fcl
import numpy as np

from clutter_gym.collision.distance import signed_distance
from clutter_gym.collision.robot_model import RobotCollisionModel
from clutter_gym.robots.state import RobotState
from clutter_gym.transforms import quat_to_matrix, yaw_quat
from clutter_gym.worlds.scene import Obstacle

#: Clearance reported when there is nothing to measure against (an empty scene without walls), metres.
NO_OBSTACLE_CLEARANCE = 1e3


@dataclass(frozen=True, slots=True)
class Contact:
    """A robot link touching or penetrating an obstacle (FCL).

    Attributes:
        link: URDF link name.
        obstacle: index of the obstacle in the scene's obstacle list.
        depth: penetration depth in metres (0 when touching within the tolerance without overlap).
        position: (3,) a contact point in the world frame.
    """

    link: str
    obstacle: int
    depth: float
    position: np.ndarray


@dataclass(frozen=True, slots=True)
class CollisionReport:
    """What FCL (and pybullet, as a cross-check) say about the robot after a step.

    Attributes:
        min_clearance: signed distance from the robot to the nearest obstacle, metres; negative = penetration.
        link_clearance: (L,) signed distance per link with geometry (``CollisionChecker.links``), capped at the
            clearance range.
        directions: (L, 3) unit vectors from each link's witness point to its obstacle's, world frame (zero
            where the link is out of range or penetrating).
        closest: (link, obstacle index) of the nearest pair, or None beyond the range.
        witness: (2, 3) witness points (on the link, on the obstacle) of that pair, world frame, or None.
        contacts: robot-link/obstacle pairs within the contact tolerance.
        self_collision: an enabled link pair in self-collision, or None.
        tunneling: shape/obstacle pairs the swept check hit that the end-of-step check found clear.
        pybullet_contacts: pybullet contact points between the robot and obstacles within the tolerance.
        disagreement: exactly one of the two engines reports environment contact.
    """

    min_clearance: float
    link_clearance: np.ndarray
    directions: np.ndarray
    closest: tuple[str, int] | None
    witness: np.ndarray | None
    contacts: tuple[Contact, ...]
    self_collision: tuple[str, str] | None = None
    tunneling: int = 0
    pybullet_contacts: int = 0
    disagreement: bool = False

    @property
    def n_contacts(self) -> int:
        return len(self.contacts)

    @property
    def in_contact(self) -> bool:
        return bool(self.contacts)


def obstacle_shape(o: Obstacle) -> fcl.CollisionGeometry:
    """FCL shape of an obstacle in its own frame (centred, cylinder along z)."""
    return fcl.Cylinder(o.radius, o.size[2]) if o.shape == "cylinder" else fcl.Box(*o.size)


def obstacle_object(o: Obstacle, shape: fcl.CollisionGeometry | None = None) -> fcl.CollisionObject:
    """FCL object for an obstacle (its bottom face at height ``o.z``), optionally with a given shape."""
    # a rotation matrix, not a quaternion: FCL's are (w, x, y, z), ours (x, y, z, w); bit for bit the matrix FCL
    # would build from the quaternion
    rotation = quat_to_matrix(np.array(yaw_quat(o.yaw)))
    return fcl.CollisionObject(shape or obstacle_shape(o), fcl.Transform(rotation, list(o.centre)))


def _half_extents(o: Obstacle) -> tuple[float, float, float]:
    """Half extents of the world-axis-aligned box around an upright obstacle."""
    if o.shape == "cylinder":
        return (o.radius, o.radius, 0.5 * o.size[2])
    c, s = abs(np.cos(o.yaw)), abs(np.sin(o.yaw))
    return (0.5 * (c * o.size[0] + s * o.size[1]), 0.5 * (s * o.size[0] + c * o.size[1]), 0.5 * o.size[2])


class CollisionChecker:
    """FCL model of one robot and the current scene.

    Args:
        model: the robot's FCL objects (fidelity, padding and ACM chosen there).
        base_link: name of the URDF base link (its pose is ``RobotState.position``/``rotation``).
        contact_tolerance: distance at or below which either engine counts a contact, metres.
        clearance_range: distances are resolved up to this range (metres); farther links report it.
        swept_speed: shapes faster than this (m/s, from their displacement over ``dt``) get a swept check;
            ``inf`` turns swept checks off.
        dt: time between two checks (the control period), seconds.
        fixed_links: links that never move relative to the world (an arm's fixed base): left out of the
            environment queries, where they would only measure their own mounting, but kept for self-collision.
    """

    def __init__(
        self,
        model: RobotCollisionModel,
        base_link: str,
        contact_tolerance: float = 1e-3,
        clearance_range: float = 0.5,
        swept_speed: float = 0.2,
        dt: float = 0.05,
        fixed_links: Sequence[str] = (),
    ) -> None:
        self.model = model
        self.links = tuple(link for link in model.links if link not in fixed_links)
        moving = [i for i, s in enumerate(model.shapes) if s.link not in fixed_links]
        self._link_of_shape = np.array([self.links.index(s.link) if s.link in self.links else -1 for s in model.shapes])
        self._base_link = base_link
        self.contact_tolerance = contact_tolerance
        self.clearance_range = clearance_range
        self.swept_speed = swept_speed
        self.dt = dt
        self._moving = np.array(moving, dtype=int)
        self._radii = np.array([s.radius for s in model.shapes])
        self._sweepers = [fcl.CollisionObject(s.hull or s.geometry, fcl.Transform()) for s in model.shapes]
        self._obstacles: list[fcl.CollisionObject] = []
        self._obstacle_index: dict[int, int] = {}
        self._obstacle_low = self._obstacle_high = np.zeros((0, 3))
        self._obstacle_bodies: frozenset[int] = frozenset()
        self._manager: fcl.DynamicAABBTreeCollisionManager | None = None
        self._contact_request = fcl.CollisionRequest(num_max_contacts=4, enable_contact=True)
        self._ccd_request = fcl.ContinuousCollisionRequest()
        self._rows: np.ndarray | None = None
        self._previous: tuple[np.ndarray, np.ndarray] | None = None

    # ------------------------------------------------------------------------------------------- scene
    def set_scene(self, obstacles: Sequence[Obstacle], bodies: Sequence[int]) -> None:
        """Rebuild the obstacle broad phase (call on reset). ``bodies`` are the matching pybullet body ids."""
        geometries = [obstacle_shape(o) for o in obstacles]
        self._obstacles = [obstacle_object(o, g) for o, g in zip(obstacles, geometries)]
        self._obstacle_index = {id(g): i for i, g in enumerate(geometries)}
        centres = np.array([o.centre for o in obstacles]).reshape(-1, 3)
        half = np.array([_half_extents(o) for o in obstacles]).reshape(-1, 3)
        self._obstacle_low, self._obstacle_high = centres - half, centres + half
        self._obstacle_bodies = frozenset(bodies)
        manager = fcl.DynamicAABBTreeCollisionManager()
        if self._obstacles:
            manager.registerObjects(self._obstacles)
        manager.setup()
        self._manager = manager
        self._previous = None  # a reset teleports the robot: nothing to sweep from

    # ------------------------------------------------------------------------------------------- queries
    def sync(self, state: RobotState) -> None:
        """Move the robot's FCL objects to the link poses in ``state``."""
        if self._rows is None:  # model row -> row of [base, *state.links]; fixed for a robot
            names = (self._base_link, *state.link_names)
            self._rows = np.array([names.index(n) for n in self.model.link_names])
        rot = np.concatenate((state.rotation[None], state.links.rotation))[self._rows]
        pos = np.concatenate((state.position[None], state.links.position))[self._rows]
        self.model.sync(pos, rot)

    def clearance(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per shape: signed distance (capped at the range), obstacle index (-1 beyond it) and witness points.

        Robot objects must be synced. One query per moving shape against the obstacle tree: FCL visits the
        obstacles nearest-box-first and prunes every subtree farther than the running best the callback hands
        back: about five narrow-phase calls per shape on the Panda, and the same cost at 1,000 and 10,000
        obstacles. (One robot-tree-vs-obstacle-tree traversal has a single bound for all shapes, the largest
        per-shape best, and made twice the narrow-phase calls.)
        """
        n = len(self.model.objects)
        best = np.full(n, self.clearance_range)
        other = np.full(n, -1)
        points = np.zeros((n, 2, 3))
        if not self._obstacles:
            return np.full(n, NO_OBSTACLE_CLEARANCE), other, points
        for i in self._moving:
            raw, j, p = self._nearest_obstacle(i, self.clearance_range + self.model.padding[i])
            if j >= 0:
                best[i], other[i], points[i] = raw - self.model.padding[i], j, p
        return best, other, points

    def _nearest_obstacle(self, i: int, bound: float) -> tuple[float, int, np.ndarray | None]:
        """(unpadded distance, obstacle index, witness points) of shape ``i``'s nearest obstacle within ``bound``."""
        shape, solid = self.model.objects[i], self.model.solid_objects[i]
        found: list = [bound, -1, None]

        def visit(o1: fcl.CollisionObject, _o2: fcl.CollisionObject, _data: object) -> tuple[bool, float]:
            # o1 is a fresh wrapper of an obstacle; the geometry a DistanceResult hands back is the very Python
            # object the obstacle was built with, so it names the obstacle. The robot shape goes first: as the
            # first argument a BVH reports world-frame witness points in order.
            d, result = signed_distance(shape, o1, solid)
            if d < found[0]:
                found[:] = d, self._obstacle_index[id(result.o2)], result.nearest_points
            # FCL visits a box only if it is strictly nearer than the bound: keep overlapping boxes in play
            return False, max(found[0], 1e-12)

        self._manager.distance(shape, None, visit)
        return found[0], found[1], found[2]

    def check(self, state: RobotState, pybullet_contacts: Sequence[tuple[int, float]] = ()) -> CollisionReport:
        """Clearance, contacts, self-collision and tunneling of the robot in ``state``.

        Args:
            state: the robot state after the step.
            pybullet_contacts: (other body id, contact distance) of the robot's pybullet contact points.
        """
        self.sync(state)
        distance, other, points = self.clearance()
        model = self.model
        n_links = len(self.links)
        link_of, moving = self._link_of_shape, self._link_of_shape >= 0
        link_clearance = np.full(n_links, min(self.clearance_range, NO_OBSTACLE_CLEARANCE))
        np.minimum.at(link_clearance, link_of[moving], distance[moving])
        directions = np.zeros((n_links, 3))
        gap = points[:, 1] - points[:, 0]
        norms = np.linalg.norm(gap, axis=1)
        closest_shape = np.full(n_links, -1)
        for i in np.argsort(-distance):  # nearest last, so each link keeps its nearest shape
            if moving[i]:
                closest_shape[link_of[i]] = i
        for link, i in enumerate(closest_shape):
            if i >= 0 and other[i] >= 0 and distance[i] > 0.0 and norms[i] > 0.0:
                directions[link] = gap[i] / norms[i]
        k = int(np.argmin(distance))
        found = other[k] >= 0
        contacts = self._contacts(distance, points)
        tunneling = self._swept()
        tol = self.contact_tolerance
        n_pb = sum(1 for body, d in pybullet_contacts if d <= tol and body in self._obstacle_bodies)
        return CollisionReport(
            min_clearance=float(distance[k]) if self._obstacles else NO_OBSTACLE_CLEARANCE,
            link_clearance=link_clearance,
            directions=directions,
            closest=(model.shapes[k].link, int(other[k])) if found else None,
            witness=points[k].copy() if found else None,
            contacts=contacts,
            self_collision=model.self_collision(),
            tunneling=tunneling,
            pybullet_contacts=n_pb,
            disagreement=bool(contacts) != (n_pb > 0),
        )

    def _contacts(self, distance: np.ndarray, points: np.ndarray) -> tuple[Contact, ...]:
        """Contacts of the shapes whose nearest obstacle is within the tolerance.

        A shape can touch several obstacles at once: every obstacle whose box meets the touching shape's
        bounding box is measured, and those within the tolerance get their penetration depth from ``fcl.collide``.
        """
        touching = np.flatnonzero(distance <= self.contact_tolerance)
        if touching.size == 0:
            return ()
        model, out = self.model, []
        centres = model.position[touching]
        reach = (self._radii[touching] + model.padding[touching] + self.contact_tolerance)[:, None]
        for k, j in self._boxes_meeting(centres - reach, centres + reach):
            i = touching[k]
            obj = model.solid_objects[i]  # a BVH's contact depths are not meaningful; its hull's are
            d = self._pair_distance(i, j)
            if d > self.contact_tolerance:
                continue
            result = fcl.CollisionResult()
            depth, where = max(0.0, -d), points[i].mean(axis=0)
            if fcl.collide(obj, self._obstacles[j], self._contact_request, result):
                deepest = max(result.contacts, key=lambda c: c.penetration_depth)
                depth = max(depth, float(deepest.penetration_depth))
                where = np.asarray(deepest.pos, dtype=float)
            out.append(Contact(model.shapes[i].link, int(j), depth + model.padding[i], where))
        return tuple(out)

    def _boxes_meeting(self, low: np.ndarray, high: np.ndarray) -> list[tuple[int, int]]:
        """(row, obstacle) pairs where the box [low, high] of a row (n, 3) overlaps the obstacle's world AABB."""
        overlap = np.all((low[:, None] <= self._obstacle_high[None]) & (high[:, None] >= self._obstacle_low[None]),
                         axis=2)
        return list(zip(*np.nonzero(overlap)))

    def _pair_distance(self, shape: int, obstacle: int) -> float:
        """Padded signed distance from a robot shape (its solid: a mesh's hull) to an obstacle, metres."""
        d, _ = signed_distance(self.model.solid_objects[shape], self._obstacles[obstacle])
        return d - self.model.padding[shape]

    def _swept(self) -> int:
        """Count swept hits, for shapes faster than ``swept_speed``, that end the step clear of the obstacle.

        Candidates are the obstacles whose axis-aligned box overlaps the box around the shape's bounding ball at
        both ends of the step.
        """
        model = self.model
        now = (model.position.copy(), model.rotation.copy())
        previous, self._previous = self._previous, now
        if previous is None or not self._obstacles or not np.isfinite(self.swept_speed):
            return 0
        radius = self._radii
        # rotation adds at most angle * radius to the travel of any point of the shape
        cos_angle = np.clip((np.einsum("nij,nij->n", now[1], previous[1]) - 1.0) / 2.0, -1.0, 1.0)
        travel = np.linalg.norm(now[0] - previous[0], axis=1) + np.arccos(cos_angle) * radius
        fast = self._moving[travel[self._moving] > self.swept_speed * self.dt]
        if fast.size == 0:
            return 0
        reach = (radius[fast] + model.padding[fast])[:, None]
        low = np.minimum(previous[0][fast], now[0][fast]) - reach
        high = np.maximum(previous[0][fast], now[0][fast]) + reach
        hits = 0
        for k, j in self._boxes_meeting(low, high):
            i = fast[k]
            sweeper, obstacle = self._sweepers[i], self._obstacles[j]
            sweeper.setRotation(previous[1][i])
            sweeper.setTranslation(previous[0][i])
            result = fcl.ContinuousCollisionResult()
            fcl.continuousCollide(sweeper, fcl.Transform(now[1][i], now[0][i]), obstacle, obstacle.getTransform(),
                                  self._ccd_request, result)
            if result.is_collide and self._pair_distance(i, j) > self.contact_tolerance:  # clear at the end
                hits += 1
        return hits
