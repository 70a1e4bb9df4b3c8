"""Robot-vs-scene clearance, contacts, self-collision and swept checks with FCL, cross-checked against pybullet.

The obstacles' FCL objects are placed, and their arrays for bounds (:mod:`bounds`) rebuilt, on reset only. Each step
moves the robot's FCL objects to the link poses the robot read in one batched call, bounds every (shape,
obstacle) pair from below in one compiled pass (in a large scene, the obstacles near the robot: searched narrow
first, and wider only while some answer is not proved exact), then:

1. each moving shape asks FCL about its obstacles in order of their bounds (:mod:`.nearest`), until no bound can beat
   the best exact distance: every link's clearance (capped at ``clearance_range``), its witness points and the closest
   obstacle, exactly as if every pair were measured. A checker made with ``per_link=False`` (for a task that needs
   only the robot's clearance) instead takes every (shape, obstacle) pair in one order of their bounds and stops at
   the first bound that cannot beat the best distance: the same minimum, nearest pair and witness points, with
   typically one or two FCL queries a step instead of one or more per shape, and only the shapes it measures moved
   in FCL;
2. pairs within ``contact_tolerance`` are enumerated as contacts with their penetration depth;
3. enabled self pairs (the ACM) are tested, after a bounding-ball filter; at a coarse level a hit counts only when
   the ``convex`` level's shapes of the two links touch as well (:mod:`confirm`);
4. shapes that moved faster than ``swept_speed`` are swept (:mod:`.swept_audit`) from their previous pose on the screw
   motion to their pose now, rotation included (:mod:`.sweep`: conservative advancement on FCL's exact distance),
   against the obstacles near their path: a hit the end-of-step check does not see is *tunneling*, unless the pair
   was in contact at the previous check (a shape leaving a contact). Mesh shapes sweep their convex hull.
"""

from __future__ import annotations

from collections.abc import Sequence

import fcl
import numpy as np

from clutter_gym.collision.bounds import ObstacleBounds
from clutter_gym.collision.distance import signed_distance
from clutter_gym.collision.nearest import NO_OBSTACLE_CLEARANCE, NearestSearch
from clutter_gym.collision.obstacles import ObstacleObjects
from clutter_gym.collision.robot_model import RobotCollisionModel
from clutter_gym.collision.swept_audit import SweptAudit
from clutter_gym.datatypes import CollisionReport, Contact, Obstacle, RobotState


class CollisionChecker:
    """FCL model of one robot and the current scene. It owns the scene's obstacle objects and pybullet bodies, and is
    composed of a :class:`NearestSearch` (:attr:`search`: each shape's nearest obstacle) and a :class:`SweptAudit`
    (:attr:`audit`: the swept check between two checks).

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
        per_link: resolve every link's clearance and direction (``CollisionReport.link_clearance``); False measures
            only the robot's nearest pair, for tasks that need no more (the module docstring).
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
        per_link: bool = True,
    ) -> None:
        self.model = model
        self.per_link = bool(per_link)
        self.links = tuple(link for link in model.links if link not in fixed_links)
        moving = np.array([i for i, s in enumerate(model.shapes) if s.link not in fixed_links], dtype=int)
        #: the moving shapes of every link in ``self.links``
        link_shapes = [[i for i, s in enumerate(model.shapes) if s.link == link] for link in self.links]
        single = all(len(s) == 1 for s in link_shapes)
        self._link_shape = np.array([s[0] for s in link_shapes]) if single else None
        self._base_link = base_link
        self.contact_tolerance = contact_tolerance
        self.clearance_range = clearance_range
        self.swept_speed = swept_speed
        self.dt = dt
        self.search = NearestSearch(model, moving, link_shapes, clearance_range, contact_tolerance)
        self.audit = SweptAudit(self.search, swept_speed, dt)
        self._obstacle_objects = ObstacleObjects()
        self._obstacle_bodies: frozenset[int] = frozenset()
        self._contact_request = fcl.CollisionRequest(num_max_contacts=4, enable_contact=True)
        self._rows: np.ndarray | None = None
        self._touching: set[tuple[int, int]] = set()  # (shape, obstacle) pairs within the tolerance at the last check

    # ------------------------------------------------------------------------------------------- scene
    def set_scene(self, obstacles: Sequence[Obstacle], bodies: Sequence[int]) -> None:
        """Rebuild the obstacle broad phase (call on reset). ``bodies`` are the matching pybullet body ids."""
        self.search.set_scene(self._obstacle_objects.place(obstacles), ObstacleBounds(obstacles))
        self._obstacle_bodies = frozenset(bodies)
        self.audit.previous = None  # a reset teleports the robot: nothing to sweep from
        self._touching = set()

    def set_obstacle_bodies(self, bodies: Sequence[int]) -> None:
        """The pybullet bodies of the obstacles now, where a large scene gave some obstacles bodies or took them back
        (``worlds/near_field.py``): pybullet's contacts are counted against these."""
        self._obstacle_bodies = frozenset(bodies)

    def move_obstacles(self, obstacles: np.ndarray, positions: np.ndarray, rotations: np.ndarray) -> None:
        """Put movable ``obstacles`` (indices into the scene's) where the physics moved them: centres (k, 3) and
        rotation matrices (k, 3, 3), world frame."""
        self.search.bounds.move(obstacles, positions, rotations)
        fcl_objects = self.search.obstacles
        for j, position, rotation in zip(obstacles, positions, rotations):
            fcl_objects[j].setTransform(fcl.Transform(rotation, position))

    # ------------------------------------------------------------------------------------------- queries
    def sync(self, state: RobotState) -> None:
        """Move the robot's FCL objects to the link poses in ``state``."""
        if self._rows is None:  # model row -> row of [base, *state.links]; fixed for a robot
            names = (self._base_link, *state.link_names)
            self._rows = np.array([names.index(n) for n in self.model.link_names])
        rot = np.concatenate((state.rotation[None], state.links.rotation))[self._rows]
        pos = np.concatenate((state.position[None], state.links.position))[self._rows]
        if self.per_link:
            self.model.sync(pos, rot)
        else:  # the nearest-pair query moves only the shapes it measures
            self.model.set_poses(pos, rot)

    def clearance(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per shape: signed distance (capped at the range), obstacle index (-1 beyond it) and witness points.

        Robot objects must be synced. Obstacles are measured nearest-bound first (:mod:`bounds`), and a shape
        stops at the first obstacle whose lower bound cannot beat its best exact distance: a shape with nothing
        in range makes no FCL call. A sphere's bound is its distance, so the spheres of a sphere set make no FCL
        call for it; their witness points are filled only where they are reported: the nearest shape of each link,
        and shapes within the contact tolerance (zeros elsewhere).
        """
        return self.search.measure()[:3]

    def check(self, state: RobotState, pybullet_contacts: Sequence[tuple[int, float]] = ()) -> CollisionReport:
        """Clearance, contacts, self-collision and tunneling of the robot in ``state``.

        Args:
            state: the robot state after the step.
            pybullet_contacts: (other body id, contact distance) of the robot's pybullet contact points.
        """
        self.sync(state)
        search = self.search
        link_clearance = directions = None
        if self.per_link:
            distance, other, points, candidates, bound, within = search.measure()
            link_clearance, directions = self._links(distance, other, points)
            k = int(np.argmin(distance))
            nearest = (float(distance[k]), k, int(other[k]), points[k].copy() if other[k] >= 0 else None)
            lower = distance[search.moving]
        elif search.obstacles:
            radii = search.search_radii()
            for within in radii:  # narrow first: the first search that proves the nearest pair exact gives it
                candidates, bound = search.lower_bounds(within=within)
                pair = search.nearest_pair(candidates, bound, within if within < radii[-1] else None)
                if pair is not None:
                    break
            assert pair is not None  # the last search is the whole range, whose answer is always exact
            nearest = pair
            lower = (bound - search.moving_padding).min(axis=1, initial=np.inf)
        else:
            candidates, bound, within = np.zeros(0, int), np.zeros((len(search.moving), 0)), np.inf
            nearest, lower = (NO_OBSTACLE_CLEARANCE, -1, -1, None), np.full(len(search.moving), np.inf)
        clearance, k, obstacle, witness = nearest
        touching_before = self._touching
        contacts = self._contacts(lower, candidates, bound)
        tunneling = self.audit.count(candidates, bound, within, touching_before, self._touching)
        tol = self.contact_tolerance
        n_pb = sum(1 for body, d in pybullet_contacts if d <= tol and body in self._obstacle_bodies)
        return CollisionReport(
            min_clearance=clearance if search.obstacles else NO_OBSTACLE_CLEARANCE,
            link_clearance=link_clearance,
            directions=directions,
            closest=(self.model.shapes[k].link, obstacle) if obstacle >= 0 else None,
            witness=witness,
            contacts=contacts,
            self_collision=self.model.self_collision(),
            tunneling=tunneling,
            pybullet_contacts=n_pb,
            disagreement=bool(contacts) != (n_pb > 0),
        )

    def _links(self, distance: np.ndarray, other: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per link: the clearance of its nearest shape (capped at the range), and the unit vector from that shape's
        witness point to its obstacle's (zero where out of range or penetrating)."""
        nearest = self._link_shape  # each link reports its nearest shape
        if nearest is None:
            nearest = np.array([s[int(np.argmin(distance[s]))] for s in self.search.link_shapes])
        link_clearance = np.minimum(distance[nearest], min(self.clearance_range, NO_OBSTACLE_CLEARANCE))
        witnesses = points[nearest]
        gap = witnesses[:, 1] - witnesses[:, 0]
        norms = np.sqrt(np.add.reduce(gap * gap, axis=1))  # np.linalg.norm(gap, axis=1) without its dispatch
        pointing = (other[nearest] >= 0) & (link_clearance > 0.0) & (norms > 0.0)
        directions = np.divide(gap, norms[:, None], out=np.zeros_like(gap), where=pointing[:, None])
        return link_clearance, directions

    def _contacts(self, lower: np.ndarray, candidates: np.ndarray, bound: np.ndarray) -> tuple[Contact, ...]:
        """Contacts of the moving shapes; ``lower`` (per moving shape) bounds each one's padded clearance from below,
        and shapes above the tolerance are skipped.

        A shape can touch several obstacles at once: every candidate obstacle whose lower bound is within the
        tolerance is measured. A contact's depth is minus the padded signed distance, the same measure as the
        clearance; ``fcl.collide`` gives only its position (its own depth estimates run deep on convex shapes), and
        where the shapes touch without overlapping, the midpoint of the pair's witness points is the position.
        """
        model, out, tol = self.model, [], self.contact_tolerance
        moving, obstacles = self.search.moving, self.search.obstacles
        self._touching = touching = set()
        for row in np.flatnonzero(lower <= tol).tolist():
            i = int(moving[row])
            obj = model.solid_object(i)  # a BVH's contacts are not meaningful; its hull's are
            for j in np.sort(candidates[bound[row] - model.padding[i] <= tol]).tolist():
                d, found = signed_distance(obj, obstacles[j])
                d -= model.padding[i]
                if d > tol:
                    continue
                result = fcl.CollisionResult()
                where = np.mean(found.nearest_points, axis=0)
                if fcl.collide(obj, obstacles[j], self._contact_request, result):
                    deepest = max(result.contacts, key=lambda c: c.penetration_depth)
                    where = np.asarray(deepest.pos, dtype=float)
                out.append(Contact(model.shapes[i].link, j, max(0.0, -d), where))
                touching.add((i, j))
        return tuple(out)

    def pair_distance(self, shape: int, obstacle: int) -> float:
        """Padded signed distance from a robot shape (its solid: a mesh's hull) to an obstacle, metres."""
        d, _ = signed_distance(self.model.solid_object(shape), self.search.obstacles[obstacle])
        return d - self.model.padding[shape]
