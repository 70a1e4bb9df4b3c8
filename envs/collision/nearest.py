"""The collision checker's search for each robot shape's nearest obstacle (a part of
:class:`~clutter_gym.collision.checker.CollisionChecker`: it owns the moving shapes' limits and the scene's FCL
obstacles and bounds, and reads the robot model the checker syncs).

Every (shape, obstacle) pair is bounded from below in one compiled pass (:mod:`.bounds`), and FCL is asked about pairs
in order of their bounds until no bound can beat the best exact distance, so every answer is the one measuring every
pair gives. A scene of more than ``SMALL_SCENE`` obstacles is searched near the robot first and wider only while some
shape's answer is not proved exact (docs/collision.md, "Large scenes").
"""

from __future__ import annotations

import fcl
import numpy as np

from clutter_gym.collision.bounds import ObstacleBounds
from clutter_gym.collision.distance import signed_distance
from clutter_gym.collision.robot_model import RobotCollisionModel

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
#: (:meth:`NearestSearch.search_radii`), so that a step's cost follows the obstacles near the robot
FIRST_SEARCH = 0.5
#: factor by which a search that cannot prove some shape's answer exact widens, up to the clearance range
WIDEN = 4.0


class NearestSearch:
    """Nearest obstacles of the moving shapes: per shape (:meth:`measure`) or the robot's nearest pair
    (:meth:`nearest_pair`), from the candidates and lower bounds of :meth:`lower_bounds`.

    Args:
        model: the robot's FCL objects, synced by the checker before every query.
        moving: indices of the shapes measured against the scene (those of links that move).
        link_shapes: the moving shapes of each link the checker reports.
        clearance_range: distances are resolved up to this range, metres.
        contact_tolerance: distance at or below which a pair is in contact, metres.
    """

    def __init__(self, model: RobotCollisionModel, moving: np.ndarray, link_shapes: list[list[int]],
                 clearance_range: float, contact_tolerance: float) -> None:
        self.model, self.moving, self.link_shapes = model, moving, link_shapes
        self.clearance_range, self.contact_tolerance = clearance_range, contact_tolerance
        self._limits_array = clearance_range + model.padding[moving]  # unpadded range per moving shape
        self.moving_padding = model.padding[moving][:, None]
        #: (moving shapes, 1) radii of their enclosing balls, widened by the slack (:meth:`lower_bounds`)
        self.slack_radii = (model.ball_radius[moving] + BOUND_SLACK)[:, None]
        lazy = model.lazy[moving]  # spheres of a sphere set: their lower bounds are their exact distances
        #: rows (of the moving shapes) answered from their bounds in one numpy pass, and those answered by FCL
        self._sphere_rows, self._other_rows = np.flatnonzero(lazy), np.flatnonzero(~lazy)
        self._other_limits = self._limits_array[self._other_rows].tolist()
        self.obstacles: list[fcl.CollisionObject] = []
        self.bounds = ObstacleBounds(())

    def set_scene(self, obstacles: list[fcl.CollisionObject], bounds: ObstacleBounds) -> None:
        """The scene's FCL obstacles and their bounds (the checker places both on reset)."""
        self.obstacles, self.bounds = obstacles, bounds

    def measure(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """:meth:`clearance`, and the candidate obstacles and lower bounds it used (rows: moving shapes) with the
        ``within`` they were searched to (:meth:`lower_bounds`).

        A large scene is searched narrow first (:meth:`search_radii`); a shape's answer is kept from the first
        search that proves it exact (:meth:`_nearest_spheres`, :meth:`_nearest_obstacles`), so every answer is the
        one a search of the whole range gives.
        """
        model, moving = self.model, self.moving
        n = len(model.objects)
        best = np.full(n, self.clearance_range)
        other = np.full(n, -1)
        points = np.zeros((n, 2, 3))
        radii = self.search_radii()
        if not self.obstacles:
            return (np.full(n, NO_OBSTACLE_CLEARANCE), other, points, np.zeros(0, int), np.zeros((len(moving), 0)),
                    radii[-1])
        spheres, others = self._sphere_rows, self._other_rows  # rows not answered yet
        answered: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # spheres in range: rows, raw, obstacles
        found: list[tuple[int, float, int, np.ndarray | None]] = []
        for within in radii:
            candidates, bound = self.lower_bounds(within=within)
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
        plus its padding (:meth:`lower_bounds`), so a lowest bound at or below that is the lowest of all; the other
        rows need a wider search.
        """
        if not bound.shape[1]:
            return rows if within is not None else rows[:0]
        nearest = np.argmin(bound[rows], axis=1)
        lowest = bound[rows, nearest]
        left = rows[:0]
        if within is not None:
            exact = lowest <= within + self.model.padding[self.moving[rows]]
            if not exact.all():
                rows, nearest, lowest, left = rows[exact], nearest[exact], lowest[exact], rows[~exact]
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
        ``within`` plus its padding (:meth:`lower_bounds`). Those obstacles come after every candidate bounded at
        or below that, so a shape whose best distance over those candidates is at or below it would stop before
        them: that answer is exact. A shape with nothing that near needs a wider search.
        """
        moving = self.moving
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
            counted = zip(shapes.tolist(), kept.sum(axis=1).tolist(), candidates[order].tolist(),
                          np.take_along_axis(lower_bounds, order, axis=1).tolist())
            results = [self._nearest_obstacle(i, nearest_first[:k], lower[:k], limit) if k else (limit, -1, None)
                       for (i, k, nearest_first, lower), limit in zip(counted, limits)]
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
        result: tuple[float, int, np.ndarray | None] = (limit, -1, None)
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
        for shapes in self.link_shapes:
            i = shapes[int(np.argmin(best[shapes]))]
            if model.lazy[i] and other[i] >= 0:
                reported.add(i)
        for i in reported:
            _, result = signed_distance(model.object(i), self.obstacles[other[i]])
            points[i] = result.nearest_points

    def search_radii(self) -> list[float]:
        """The ``within`` of each search for obstacles (:meth:`lower_bounds`), narrowest first, the last the whole
        range (the clearance range or the contact tolerance, whichever is larger).

        A small scene bounds every obstacle at once. A larger one starts at ``FIRST_SEARCH`` (never below the
        contact tolerance, so that every contact is among the first candidates) and widens ``WIDEN`` times: the
        nearest obstacles of a robot among clutter are found in the first search, whatever the scene's size.
        """
        tol = self.contact_tolerance
        full = max(self.clearance_range, tol)
        radii = [full]
        if len(self.bounds) > SMALL_SCENE:
            radii = [max(min(FIRST_SEARCH, self.clearance_range), tol)]
            while radii[-1] < full:
                radii.append(min(WIDEN * radii[-1], full))
        return radii

    def lower_bounds(self, grow: np.ndarray | None = None, within: float | None = None
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
        bounds, model, moving = self.bounds, self.model, self.moving
        centres = model.ball_centres()[moving]
        radii = self.slack_radii if grow is None else (model.ball_radius[moving] + grow + BOUND_SLACK)[:, None]
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
            d, result = signed_distance(shape, self.obstacles[j], solid)
            if d < best:
                best, nearest, witness = d, j, result.nearest_points
        return best, nearest, witness

    def nearest_pair(self, candidates: np.ndarray, bound: np.ndarray, within: float | None = None
                      ) -> tuple[float, int, int, np.ndarray | None] | None:
        """(padded signed distance, shape, obstacle index, witness points) of the robot's nearest pair within the
        clearance range; (the range, -1, -1, None) when no pair is in it.

        Pairs are measured in ascending order of their padded lower bounds until a bound exceeds the best distance,
        so no unmeasured pair can be nearer. Among equal distances the lowest shape index wins, and for one shape the
        pair met first, as :meth:`measure` and :meth:`check` pick them.

        After a search to a narrower ``within`` than the range, every pair left out has a padded bound above
        ``within`` (:meth:`lower_bounds`) and comes after every pair bounded at or below it: those pairs are
        measured, and a best distance at or below ``within`` stops the measuring before the pairs left out, so it
        is the answer; otherwise the answer is None (search wider).
        """
        model, moving = self.model, self.moving
        padded = bound - self.moving_padding  # lower bounds on the padded distances
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
                d, found = signed_distance(model.object(i), self.obstacles[j], model.solid_object(i))
                d -= model.padding[i]
            if d < best or (d == best and i < shape):
                best, shape, obstacle, result = d, i, j, found
        if within is not None and best > within:
            return None
        if shape < 0:
            return best, shape, obstacle, None
        if result is None:
            _, result = signed_distance(model.object(shape), self.obstacles[obstacle])
        return best, shape, obstacle, np.asarray(result.nearest_points, dtype=float)
