"""Robot-vs-scene clearance, contacts, self-collision and swept checks with FCL, cross-checked against pybullet.

The obstacles' FCL objects are placed, and their arrays for bounds (:mod:`bounds`) rebuilt, on reset only. Each step
moves the robot's FCL objects to the link poses the robot read in one batched call, bounds every (shape,
obstacle) pair from below in one compiled pass (in a large scene, the obstacles near the robot: searched narrow
first, and wider only while some answer is not proved exact), then:

1. each moving shape asks FCL about its obstacles in order of their bounds, until no bound can beat the best
   exact distance: every link's clearance (capped at ``clearance_range``), its witness points and the closest
   obstacle, exactly as if every pair were measured. A checker made with ``per_link=False`` (for a task that needs
   only the robot's clearance) instead takes every (shape, obstacle) pair in one order of their bounds and stops at
   the first bound that cannot beat the best distance: the same minimum, nearest pair and witness points, with
   typically one or two FCL queries a step instead of one or more per shape, and only the shapes it measures moved
   in FCL;
2. pairs within ``contact_tolerance`` are enumerated as contacts with their penetration depth;
3. enabled self pairs (the ACM) are tested, after a bounding-ball filter; at a coarse level a hit counts only when
   the ``convex`` level's shapes of the two links touch as well (:mod:`confirm`);
4. shapes that moved faster than ``swept_speed`` are swept from their previous pose on the screw motion to their
   pose now, rotation included (:mod:`.sweep`: conservative advancement on FCL's exact distance), against the
   obstacles near their path: a hit the end-of-step check does not see is *tunneling*, unless the pair was in
   contact at the previous check (a shape leaving a contact). Mesh shapes sweep their convex hull.
"""

from __future__ import annotations

from collections.abc import Sequence

import fcl
import numpy as np

from clutter_gym.collision.bounds import ObstacleBounds
from clutter_gym.collision.distance import signed_distance
from clutter_gym.collision.kernels import shape_travel
from clutter_gym.collision.obstacles import ObstacleObjects
from clutter_gym.collision.robot_model import RobotCollisionModel
from clutter_gym.collision.sweep import ScrewMotion, time_of_impact
from clutter_gym.datatypes import CollisionReport, Contact, Obstacle, RobotState

#: Times along a swept shape's motion at which its enclosing ball is measured before the exact sweep (0 and 1 included)
BALL_SAMPLES = 9
#: Clearance reported when there is nothing to measure against (an empty scene without walls), metres.
NO_OBSTACLE_CLEARANCE = 1e3
#: scenes with at most this many obstacles bound every pair; larger ones first keep those near the robot. The bounds
#: cost numpy's per-call overhead more than their arithmetic: for 14 shapes every pair costs less than filtering up to
#: about 190 obstacles (docs/collision.md)
SMALL_SCENE = 128
#: metres taken off every bound, so that rounding in its arithmetic cannot lift it above an exact distance
BOUND_SLACK = 1e-9
#: in a scene larger than ``SMALL_SCENE``, a shape's candidates are sorted this many at a time (nearest first)
NEAREST_FIRST = 16
#: in a scene larger than ``SMALL_SCENE``, obstacles are first searched this far (metres) beyond the robot's reach
#: (:meth:`CollisionChecker._search_radii`), so that a step's cost follows the obstacles near the robot
FIRST_SEARCH = 0.5
#: factor by which a search that cannot prove some shape's answer exact widens, up to the clearance range
WIDEN = 4.0


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
        moving = [i for i, s in enumerate(model.shapes) if s.link not in fixed_links]
        #: the moving shapes of every link in ``self.links``
        self._link_shapes = [[i for i, s in enumerate(model.shapes) if s.link == link] for link in self.links]
        single = all(len(s) == 1 for s in self._link_shapes)
        self._link_shape = np.array([s[0] for s in self._link_shapes]) if single else None
        self._base_link = base_link
        self.contact_tolerance = contact_tolerance
        self.clearance_range = clearance_range
        self.swept_speed = swept_speed
        self.dt = dt
        self._moving = np.array(moving, dtype=int)
        self._limits_array = clearance_range + model.padding[self._moving]  # unpadded range per moving shape
        self._moving_padding = model.padding[self._moving][:, None]
        self._radii = np.array([s.radius for s in model.shapes])  # about each shape's origin
        self._ball_offsets = np.array([s.bounding_ball[0] for s in model.shapes], dtype=float).reshape(-1, 3)
        #: (moving shapes, 1) radii of their enclosing balls, widened by the slack (:meth:`_lower_bounds`)
        self._slack_radii = (model.ball_radius[self._moving] + BOUND_SLACK)[:, None]
        lazy = model.lazy[self._moving]  # spheres of a sphere set: their lower bounds are their exact distances
        #: rows (of the moving shapes) answered from their bounds in one numpy pass, and those answered by FCL
        self._sphere_rows, self._other_rows = np.flatnonzero(lazy), np.flatnonzero(~lazy)
        self._other_limits = self._limits_array[self._other_rows].tolist()
        self._sweepers = [fcl.CollisionObject(s.hull or s.geometry, fcl.Transform()) for s in model.shapes]
        self._obstacles: list[fcl.CollisionObject] = []
        self._obstacle_objects = ObstacleObjects()
        self._bounds = ObstacleBounds(())
        self._obstacle_bodies: frozenset[int] = frozenset()
        self._contact_request = fcl.CollisionRequest(num_max_contacts=4, enable_contact=True)
        self._rows: np.ndarray | None = None
        self._previous: tuple[np.ndarray, np.ndarray] | None = None
        self._touching: set[tuple[int, int]] = set()

    # ------------------------------------------------------------------------------------------- scene
    def set_scene(self, obstacles: Sequence[Obstacle], bodies: Sequence[int]) -> None:
        """Rebuild the obstacle broad phase (call on reset). ``bodies`` are the matching pybullet body ids."""
        self._obstacles = self._obstacle_objects.place(obstacles)
        self._bounds = ObstacleBounds(obstacles)
        self._obstacle_bodies = frozenset(bodies)
        self._previous = None  # a reset teleports the robot: nothing to sweep from
        self._touching: set[tuple[int, int]] = set()  # (shape, obstacle) pairs within the tolerance at the last check

    def set_obstacle_bodies(self, bodies: Sequence[int]) -> None:
        """The pybullet bodies of the obstacles now, where a large scene gave some obstacles bodies or took them back
        (``worlds/near_field.py``): pybullet's contacts are counted against these."""
        self._obstacle_bodies = frozenset(bodies)

    def move_obstacles(self, obstacles: np.ndarray, positions: np.ndarray, rotations: np.ndarray) -> None:
        """Put movable ``obstacles`` (indices into the scene's) where the physics moved them: centres (k, 3) and
        rotation matrices (k, 3, 3), world frame."""
        self._bounds.move(obstacles, positions, rotations)
        for j, position, rotation in zip(obstacles, positions, rotations):
            self._obstacles[j].setTransform(fcl.Transform(rotation, position))

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
        return self._measure()[:3]

    def _measure(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """:meth:`clearance`, and the candidate obstacles and lower bounds it used (rows: moving shapes) with the
        ``within`` they were searched to (:meth:`_lower_bounds`).

        A large scene is searched narrow first (:meth:`_search_radii`); a shape's answer is kept from the first
        search that proves it exact (:meth:`_nearest_spheres`, :meth:`_nearest_obstacles`), so every answer is the
        one a search of the whole range gives.
        """
        model, moving = self.model, self._moving
        n = len(model.objects)
        best = np.full(n, self.clearance_range)
        other = np.full(n, -1)
        points = np.zeros((n, 2, 3))
        radii = self._search_radii()
        if not self._obstacles:
            return (np.full(n, NO_OBSTACLE_CLEARANCE), other, points, np.zeros(0, int), np.zeros((len(moving), 0)),
                    radii[-1])
        spheres, others = self._sphere_rows, self._other_rows  # rows not answered yet
        answered: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # spheres in range: rows, raw, obstacles
        found: list[tuple[int, float, int, np.ndarray | None]] = []
        for within in radii:
            candidates, bound = self._lower_bounds(within=within)
            narrow = within if within < radii[-1] else None
            if len(spheres):
                spheres = self._nearest_spheres(spheres, candidates, bound, narrow, answered)
            if len(others):
                others = self._nearest_obstacles(others, candidates, bound, narrow, found)
            if not len(spheres) and not len(others):
                break
        if len(self._sphere_rows):
            rows, raw, obstacles = (np.concatenate(parts) for parts in zip(*answered)) if answered else (
                np.zeros(0, int), np.zeros(0), np.zeros(0, int))
            spheres = moving[rows]
            best[spheres], other[spheres] = raw - model.padding[spheres], obstacles
            self._sphere_witnesses(spheres, best, other, points)
        for i, raw_i, j, p in found:
            if j >= 0:
                best[i], other[i], points[i] = raw_i - model.padding[i], j, p
        return best, other, points, candidates, bound, within

    def _nearest_spheres(self, rows: np.ndarray, candidates: np.ndarray, bound: np.ndarray, within: float | None,
                         answered: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> np.ndarray:
        """Answer the sphere ``rows`` (of the moving shapes) from their bounds: append (rows, unpadded distance,
        obstacle) of those in range to ``answered``, and return the rows left unanswered.

        A sphere's bound is its distance, so its nearest obstacle is its lowest bound (the first of equals). After a
        search to a narrower ``within`` than the range, every obstacle left out bounds the sphere above ``within``
        plus its padding (:meth:`_lower_bounds`), so a lowest bound at or below that is the lowest of all; the other
        rows need a wider search.
        """
        if not bound.shape[1]:
            return rows if within is not None else rows[:0]
        nearest = np.argmin(bound[rows], axis=1)
        lowest = bound[rows, nearest]
        if within is not None:
            exact = lowest <= within + self.model.padding[self._moving[rows]]
            if not exact.all():
                rows, nearest, lowest, left = rows[exact], nearest[exact], lowest[exact], rows[~exact]
            else:
                left = rows[:0]
        else:
            left = rows[:0]
        raw = lowest + BOUND_SLACK
        in_range = raw < self._limits_array[rows]
        answered.append((rows[in_range], raw[in_range], candidates[nearest[in_range]]))
        return left

    def _nearest_obstacles(self, rows: np.ndarray, candidates: np.ndarray, bound: np.ndarray, within: float | None,
                           found: list[tuple[int, float, int, np.ndarray | None]]) -> np.ndarray:
        """:meth:`_nearest_obstacle` of the moving shapes in ``rows`` (not spheres) over ``candidates`` in ascending
        (stable) order of their bounds: append (shape, unpadded distance, obstacle, witness points) of each one
        answered to ``found``, and return the rows left unanswered.

        After a search to a narrower ``within`` than the range, every obstacle left out bounds a shape above
        ``within`` plus its padding (:meth:`_lower_bounds`). Those obstacles come after every candidate bounded at
        or below that, so a shape whose best distance over those candidates is at or below it would stop before
        them: that answer is exact. A shape with nothing that near needs a wider search.
        """
        moving = self._moving
        if within is None:
            shapes, lower_bounds, limits = moving, bound, self._other_limits
            if len(rows) < len(moving):
                shapes, lower_bounds = moving[rows], bound[rows]
            if len(rows) < len(self._other_rows):
                limits = self._limits_array[rows].tolist()
            if lower_bounds.shape[1] > SMALL_SCENE:
                results = [self._nearest_in_order(i, candidates, lower, limit)
                           for i, lower, limit in zip(shapes.tolist(), lower_bounds, limits)]
            else:
                order = np.argsort(lower_bounds, axis=1, kind="stable")
                ordered = zip(shapes.tolist(), candidates[order].tolist(), np.sort(lower_bounds, axis=1).tolist())
                results = [self._nearest_obstacle(i, nearest_first, lower, limit)
                           for (i, nearest_first, lower), limit in zip(ordered, limits)]
            found.extend((i, *result) for i, result in zip(shapes.tolist(), results))
            return rows[:0]
        if not bound.shape[1]:
            return rows
        shapes, lower_bounds = moving[rows], bound[rows]
        cutoffs = within + self.model.padding[shapes]
        kept = lower_bounds <= cutoffs[:, None]
        limits, left = self._limits_array[rows].tolist(), []
        if lower_bounds.shape[1] > SMALL_SCENE:
            results = [self._nearest_kept(i, candidates, lower, np.flatnonzero(k), limit)
                       for i, k, lower, limit in zip(shapes.tolist(), kept, lower_bounds, limits)]
        else:  # one stable sort for every row, the bounds above a row's cutoff last (and then left out)
            order = np.argsort(np.where(kept, lower_bounds, np.inf), axis=1, kind="stable")
            ordered = zip(shapes.tolist(), kept.sum(axis=1).tolist(), candidates[order].tolist(),
                          np.take_along_axis(lower_bounds, order, axis=1).tolist())
            results = [self._nearest_obstacle(i, nearest_first[:k], lower[:k], limit) if k else (limit, -1, None)
                       for (i, k, nearest_first, lower), limit in zip(ordered, limits)]
        for row, i, result, cutoff in zip(rows.tolist(), shapes.tolist(), results, cutoffs.tolist()):
            if result[0] <= cutoff:
                found.append((i, *result))
            else:
                left.append(row)
        return np.array(left, dtype=int)

    def _nearest_kept(self, i: int, candidates: np.ndarray, lower: np.ndarray, kept: np.ndarray, limit: float
                      ) -> tuple[float, int, np.ndarray | None]:
        """:meth:`_nearest_obstacle` over the ``kept`` columns (ascending) of ``candidates`` in ascending (stable)
        order of their bounds ``lower``: :meth:`_nearest_in_order` where they are many."""
        if kept.size > SMALL_SCENE:
            return self._nearest_in_order(i, candidates[kept], lower[kept], limit)
        kept = kept[np.argsort(lower[kept], kind="stable")]
        return self._nearest_obstacle(i, candidates[kept].tolist(), lower[kept].tolist(), limit)

    def _nearest_in_order(self, i: int, candidates: np.ndarray, lower: np.ndarray, limit: float
                          ) -> tuple[float, int, np.ndarray | None]:
        """:meth:`_nearest_obstacle` over ``candidates`` in ascending (stable) order of their bounds ``lower``,
        sorting only as far as it needs: the ``NEAREST_FIRST`` lowest bounds (and their ties) first, the rest only
        when those leave a bound that could still beat the best distance."""
        threshold = np.partition(lower, NEAREST_FIRST - 1)[NEAREST_FIRST - 1]
        result = (limit, -1, None)
        for part in (np.flatnonzero(lower <= threshold), np.flatnonzero(lower > threshold)):
            if part.size == 0 or lower[part].min() >= result[0]:
                break
            part = part[np.argsort(lower[part], kind="stable")]
            found = self._nearest_obstacle(i, candidates[part].tolist(), lower[part].tolist(), result[0])
            if found[1] >= 0:
                result = found
        return result

    def _sphere_witnesses(self, spheres: np.ndarray, best: np.ndarray, other: np.ndarray, points: np.ndarray) -> None:
        """Witness points, from FCL, of the spheres in range that are reported: the nearest shape of their link
        (the first of equals, as :meth:`check` picks it) or within the contact tolerance. Call after every sphere's
        ``best`` is set and before the other shapes' are: a link's nearest shape so far is then its nearest sphere,
        and a link whose nearest shape is not a sphere gets a witness it does not report."""
        model = self.model
        reported = set(spheres[best[spheres] <= self.contact_tolerance].tolist())
        for shapes in self._link_shapes:
            i = shapes[int(np.argmin(best[shapes]))]
            if model.lazy[i] and other[i] >= 0:
                reported.add(i)
        for i in reported:
            _, result = signed_distance(model.object(i), self._obstacles[other[i]])
            points[i] = result.nearest_points

    def _search_radii(self) -> list[float]:
        """The ``within`` of each search for obstacles (:meth:`_lower_bounds`), narrowest first, the last the whole
        range (the clearance range or the contact tolerance, whichever is larger).

        A small scene bounds every obstacle at once. A larger one starts at ``FIRST_SEARCH`` (never below the
        contact tolerance, so that every contact is among the first candidates) and widens ``WIDEN`` times: the
        nearest obstacles of a robot among clutter are found in the first search, whatever the scene's size.
        """
        tol = self.contact_tolerance
        full = max(self.clearance_range, tol)
        radii = [full]
        if len(self._bounds) > SMALL_SCENE:
            radii = [max(min(FIRST_SEARCH, self.clearance_range), tol)]
            while radii[-1] < full:
                radii.append(min(WIDEN * radii[-1], full))
        return radii

    def _lower_bounds(self, grow: np.ndarray | None = None, within: float | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Candidate obstacles (indices) and lower bounds (moving shapes, candidates) on their unpadded distances.

        The balls are the moving shapes' enclosing balls, their radii grown by ``grow`` (per moving shape) if given.
        In a large scene, obstacles farther than ``within`` (default, and at most: the clearance range or the contact
        tolerance, whichever is larger) plus padding from every ball are left out. Every obstacle left out then
        bounds every shape above ``within`` plus the shape's padding: its enclosing ball is farther than ``reach``
        plus ``within`` from ``middle``, and no ball reaches farther than ``reach`` less its shape's padding from
        there. A narrower ``within`` is searched ``BOUND_SLACK`` wider, so that rounding in the bounds cannot take
        that away; the whole range is searched exactly as far, whichever obstacles it keeps are bounded beyond it.
        """
        bounds, model, moving = self._bounds, self.model, self._moving
        centres = model.ball_centres()[moving]
        radii = self._slack_radii if grow is None else (model.ball_radius[moving] + grow + BOUND_SLACK)[:, None]
        if len(bounds) <= SMALL_SCENE:
            return bounds.index, bounds.signed_distance(centres) - radii
        middle = 0.5 * (centres.min(axis=0) + centres.max(axis=0))
        reach = float((np.linalg.norm(centres - middle, axis=1) + radii[:, 0] + model.padding[moving]).max())
        full = max(self.clearance_range, self.contact_tolerance)
        columns = bounds.near(middle, reach + full if within is None or within >= full
                              else reach + within + BOUND_SLACK)
        return bounds.index[columns], bounds.signed_distance(centres, columns) - radii

    def _nearest_obstacle(self, i: int, obstacles: list[int], lower: list[float], limit: float
                          ) -> tuple[float, int, np.ndarray | None]:
        """(unpadded distance, obstacle index, witness points) of shape ``i``'s nearest obstacle within ``limit``.

        ``obstacles`` come in ascending order of their lower bounds ``lower``.
        """
        shape, solid = self.model.object(i), self.model.solid_object(i)  # not a lazy sphere
        best, nearest, witness = limit, -1, None
        for j, bound in zip(obstacles, lower):
            if bound >= best:
                break
            # the robot shape goes first: as the first argument a BVH reports world-frame witness points in order
            d, result = signed_distance(shape, self._obstacles[j], solid)
            if d < best:
                best, nearest, witness = d, j, result.nearest_points
        return best, nearest, witness

    def check(self, state: RobotState, pybullet_contacts: Sequence[tuple[int, float]] = ()) -> CollisionReport:
        """Clearance, contacts, self-collision and tunneling of the robot in ``state``.

        Args:
            state: the robot state after the step.
            pybullet_contacts: (other body id, contact distance) of the robot's pybullet contact points.
        """
        self.sync(state)
        link_clearance = directions = None
        if self.per_link:
            distance, other, points, candidates, bound, within = self._measure()
            link_clearance, directions = self._links(distance, other, points)
            k = int(np.argmin(distance))
            nearest = (float(distance[k]), k, int(other[k]), points[k].copy() if other[k] >= 0 else None)
            lower = distance[self._moving]
        elif self._obstacles:
            radii = self._search_radii()
            for within in radii:  # narrow first: the first search that proves the nearest pair exact gives it
                candidates, bound = self._lower_bounds(within=within)
                pair = self._nearest_pair(candidates, bound, within if within < radii[-1] else None)
                if pair is not None:
                    break
            assert pair is not None  # the last search is the whole range, whose answer is always exact
            nearest = pair
            lower = (bound - self._moving_padding).min(axis=1, initial=np.inf)
        else:
            candidates, bound, within = np.zeros(0, int), np.zeros((len(self._moving), 0)), np.inf
            nearest, lower = (NO_OBSTACLE_CLEARANCE, -1, -1, None), np.full(len(self._moving), np.inf)
        clearance, k, obstacle, witness = nearest
        touching_before = self._touching
        contacts = self._contacts(lower, candidates, bound)
        tunneling = self._swept(candidates, bound, within, touching_before)
        tol = self.contact_tolerance
        n_pb = sum(1 for body, d in pybullet_contacts if d <= tol and body in self._obstacle_bodies)
        return CollisionReport(
            min_clearance=clearance if self._obstacles else NO_OBSTACLE_CLEARANCE,
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
            nearest = np.array([s[int(np.argmin(distance[s]))] for s in self._link_shapes])
        link_clearance = np.minimum(distance[nearest], min(self.clearance_range, NO_OBSTACLE_CLEARANCE))
        witnesses = points[nearest]
        gap = witnesses[:, 1] - witnesses[:, 0]
        norms = np.sqrt(np.add.reduce(gap * gap, axis=1))  # np.linalg.norm(gap, axis=1) without its dispatch
        pointing = (other[nearest] >= 0) & (link_clearance > 0.0) & (norms > 0.0)
        directions = np.divide(gap, norms[:, None], out=np.zeros_like(gap), where=pointing[:, None])
        return link_clearance, directions

    def _nearest_pair(self, candidates: np.ndarray, bound: np.ndarray, within: float | None = None
                      ) -> tuple[float, int, int, np.ndarray | None] | None:
        """(padded signed distance, shape, obstacle index, witness points) of the robot's nearest pair within the
        clearance range; (the range, -1, -1, None) when no pair is in it.

        Pairs are measured in ascending order of their padded lower bounds until a bound exceeds the best distance,
        so no unmeasured pair can be nearer. Among equal distances the lowest shape index wins, and for one shape the
        pair met first, as :meth:`_measure` and :meth:`check` pick them.

        After a search to a narrower ``within`` than the range, every pair left out has a padded bound above
        ``within`` (:meth:`_lower_bounds`) and comes after every pair bounded at or below it: those pairs are
        measured, and a best distance at or below ``within`` stops the measuring before the pairs left out, so it
        is the answer; otherwise the answer is None (search wider).
        """
        model, moving = self.model, self._moving
        padded = bound - self._moving_padding  # lower bounds on the padded distances
        rows, columns = np.nonzero(padded < self.clearance_range if within is None else padded <= within)
        best, shape, obstacle, result = self.clearance_range, -1, -1, None
        if rows.size == 0:
            return (best, shape, obstacle, None) if within is None else None
        lower = padded[rows, columns]
        order = np.lexsort((rows, lower))
        shapes, obstacles = moving[rows[order]].tolist(), candidates[columns[order]].tolist()
        for i, j, b in zip(shapes, obstacles, lower[order].tolist()):
            if b > best:
                break
            if model.lazy[i]:  # a sphere of a sphere set: its bound is its distance, witness points found below
                d, found = b + BOUND_SLACK, None
            else:
                d, found = signed_distance(model.object(i), self._obstacles[j], model.solid_object(i))
                d -= model.padding[i]
            if d < best or (d == best and i < shape):
                best, shape, obstacle, result = d, i, j, found
        if within is not None and best > within:
            return None
        if shape < 0:
            return best, shape, obstacle, None
        if result is None:
            _, result = signed_distance(model.object(shape), self._obstacles[obstacle])
        return best, shape, obstacle, np.asarray(result.nearest_points, dtype=float)

    def _contacts(self, lower: np.ndarray, candidates: np.ndarray, bound: np.ndarray) -> tuple[Contact, ...]:
        """Contacts of the moving shapes; ``lower`` (per moving shape) bounds each one's padded clearance from below,
        and shapes above the tolerance are skipped.

        A shape can touch several obstacles at once: every candidate obstacle whose lower bound is within the
        tolerance is measured. A contact's depth is minus the padded signed distance, the same measure as the
        clearance; ``fcl.collide`` gives only its position (its own depth estimates run deep on convex shapes), and
        where the shapes touch without overlapping, the midpoint of the pair's witness points is the position.
        """
        model, out, tol = self.model, [], self.contact_tolerance
        self._touching = touching = set()
        for row in np.flatnonzero(lower <= tol).tolist():
            i = int(self._moving[row])
            obj = model.solid_object(i)  # a BVH's contacts are not meaningful; its hull's are
            for j in np.sort(candidates[bound[row] - model.padding[i] <= tol]).tolist():
                d, found = signed_distance(obj, self._obstacles[j])
                d -= model.padding[i]
                if d > tol:
                    continue
                result = fcl.CollisionResult()
                where = np.mean(found.nearest_points, axis=0)
                if fcl.collide(obj, self._obstacles[j], self._contact_request, result):
                    deepest = max(result.contacts, key=lambda c: c.penetration_depth)
                    where = np.asarray(deepest.pos, dtype=float)
                out.append(Contact(model.shapes[i].link, j, max(0.0, -d), where))
                touching.add((i, j))
        return tuple(out)

    def pair_distance(self, shape: int, obstacle: int) -> float:
        """Padded signed distance from a robot shape (its solid: a mesh's hull) to an obstacle, metres."""
        d, _ = signed_distance(self.model.solid_object(shape), self._obstacles[obstacle])
        return d - self.model.padding[shape]

    def _swept(self, candidates: np.ndarray, bound: np.ndarray, within: float,
               touching_before: set[tuple[int, int]]) -> int:
        """Count swept hits, for shapes faster than ``swept_speed``, that end the step clear of the obstacle.

        ``candidates`` and ``bound`` are the end-of-step lower bounds (rows: moving shapes), searched to ``within``
        (:meth:`_lower_bounds`). No point of a shape moved farther than its ``travel`` during the step, so the bound
        less the travel bounds the sweep. A pair in ``touching_before`` (in contact at the last check) that ends
        clear left its contact: the sweep hits it at its start, which is no tunneling.
        """
        model = self.model
        now = (model.position, model.rotation)  # sync replaces these arrays, never writes into them
        previous, self._previous = self._previous, now
        if previous is None or not self._obstacles or not np.isfinite(self.swept_speed):
            return 0
        moving = self._moving
        travel = shape_travel(now[0], now[1], previous[0], previous[1], self._radii, moving)
        rows = np.flatnonzero(travel > self.swept_speed * self.dt)
        if rows.size == 0:
            return 0
        travel = travel[rows]
        tol = self.contact_tolerance
        needed, full = float(travel.max()) + tol, max(self.clearance_range, tol)
        if len(candidates) < len(self._obstacles) and within < min(needed, full):
            # obstacles left out of a narrow search may be in the way: search as far as the sweeps reach (the whole
            # range beyond it), which keeps every pair whose bound less the travel is within the tolerance
            candidates, bound = self._lower_bounds(within=needed if needed <= self.clearance_range else full)
        if len(candidates) < len(self._obstacles) and needed > self.clearance_range:
            # obstacles left out of the end-of-step bounds may be in the way: bound the whole sweeps instead
            grown = np.zeros(len(moving))
            grown[rows] = travel
            candidates, bound = self._lower_bounds(grow=grown)
            reach = bound[rows]
        else:
            reach = bound[rows] - travel[:, None]
        near = reach <= tol
        if not near.any():
            return 0
        # No point of a shape leaves the cones of radius travel * t about its start and travel * (1 - t) about its
        # end, so the sweep stays farther from an obstacle than (start bound + end bound - travel) / 2: only pairs
        # whose bounds at both ends leave that within the tolerance are swept (an approach that ends clear is not).
        start_centres = model.ball_centres_at(previous[0], previous[1])[moving[rows]]
        start = self._bounds.signed_distance_to(start_centres, candidates) - self._slack_radii[rows]
        near &= start + reach <= 2.0 * tol
        touching_now = self._touching  # the pairs within the tolerance now (the contacts, found before the sweep)
        hits = 0
        for row in np.flatnonzero(near.any(axis=1)):
            i = int(moving[rows[row]])
            # leaving a contact, or ending in one, is no tunneling: the end-of-step check reports that
            obstacles = [j for j in candidates[near[row]].tolist()
                         if (i, j) not in touching_before and (i, j) not in touching_now]
            if not obstacles:
                continue
            motion = ScrewMotion(previous[1][i], previous[0][i], now[1][i], now[0][i])
            reach_i = tol + model.padding[i]
            for j in self._ball_sweep_survivors(i, motion, obstacles, reach_i):
                if time_of_impact(self._sweepers[i], self._radii[i], motion, self._obstacles[j], reach_i) is not None:
                    hits += 1
        return hits

    def _ball_sweep_survivors(self, shape: int, motion: ScrewMotion, obstacles: list[int], reach: float) -> list[int]:
        """The ``obstacles`` that the enclosing ball of ``shape`` may come within ``reach`` of on ``motion``: its
        centre's exact distance to each at :data:`BALL_SAMPLES` times, and between two samples the cones of the path
        length between them (half of it beyond the mean of the two distances). The rest need no sweep."""
        offset = self._ball_offsets[shape]
        centres = motion.path(offset, BALL_SAMPLES)
        gap = self._bounds.signed_distance_to(centres, np.array(obstacles)) - (self.model.ball_radius[shape]
                                                                              + BOUND_SLACK)
        segment = motion.travel(float(np.linalg.norm(offset))) / (BALL_SAMPLES - 1)
        lowest = (0.5 * (gap[:-1] + gap[1:] - segment)).min(axis=0)
        return [j for j, d in zip(obstacles, lowest.tolist()) if d <= reach]
