"""Joint-space paths that line the hand up in front of a covered target and then go straight in.

A target with something above it (a compartment of a shelf) can only be reached from the side. RRT-Connect from
random IK goals (:mod:`clutter_gym.planning.joint_space`) reaches it with a different hand orientation and a
different path on every layout. The paths here end one way for every target instead: the hand's approach axis
pointing away from the arm's base, pitched from level by the first of a few angles that clears, its fingers'
opening level (:mod:`clutter_gym.planning.hand_pose`); a pre-insertion configuration that far back, reached by the
planner; then a straight insertion through IK points a few centimetres apart. Targets in the open keep the
planner's path.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.planning.hand_pose import approach_axis, hand_axis
from clutter_gym.planning.joint_space import ArmPlanner, _edge_free, rrt_connect, shortcut
from clutter_gym.planning.path import RESOLUTION, JointPath
from clutter_gym.robots.arm_model import ArmModel

#: How far back along the approach axis the insertion starts, metres: the hand clear of a shelf's front.
STANDOFF = 0.16
#: Spacing of the IK points along the insertion, metres.
INSERT_STEP = 0.04
#: How far short of the target the insertion ends, metres: inside ClutterReach's success radius (0.05 m), and
#: the hand's back clear of a compartment's front edge.
SHORT = 0.03
#: The hand's pitch below horizontal, radians, tried in this order: a compartment at the shoulder's height is
#: out of the Panda's reach with the hand level.
PITCHES = (0.0, np.radians(15.0), np.radians(30.0))
#: Least clearance of the insertion's configurations, metres: the planner's margin (0.02) leaves no lined-up way
#: into the Panda's reach of a 0.2 m compartment.
INSERT_MARGIN = 0.01
#: Random IK seeds besides those around the start: one fixed set (the same for every target), so that a target's
#: insertion is one function of the target and the start.
EXTRA_SEEDS = 28


def covered(target: np.ndarray, obstacles: Sequence[Obstacle]) -> bool:
    """Whether an obstacle's footprint holds ``target``'s (x, y) with its bottom above ``target``: the target lies
    under a board, so the hand must come in from the side."""
    for o in obstacles:
        if o.z <= target[2]:
            continue
        c, s = np.cos(o.yaw), np.sin(o.yaw)
        dx, dy = target[0] - o.position[0], target[1] - o.position[1]
        u, v = c * dx + s * dy, -s * dx + c * dy
        if o.shape == "box" and abs(u) <= 0.5 * o.size[0] and abs(v) <= 0.5 * o.size[1]:
            return True
        if o.shape == "cylinder" and np.hypot(dx, dy) <= 0.5 * o.size[0]:
            return True
    return False


class LineUpPlanner(ArmPlanner):
    """:class:`~clutter_gym.planning.joint_space.ArmPlanner` whose paths to a covered target (:func:`covered`) end
    lined up: the planner's path to a pre-insertion configuration ``STANDOFF`` metres back along the approach axis
    (:func:`approach_axis`), then straight in. A target in the open, or a covered one with no clear lined-up
    configurations, gets the planner's own path."""

    def __init__(self, margin: float = 0.02, fidelity: str = "convex", arm: ArmModel | None = None) -> None:
        super().__init__(margin, fidelity, arm)
        self.hand = self.checker.hand

    def plan(self, obstacles: Sequence[Obstacle], start: np.ndarray, target: np.ndarray,
             rng: np.random.Generator) -> np.ndarray | None:
        if covered(target, obstacles):
            self.checker.set_obstacles(obstacles)
            insertion = self.insertion(start, np.asarray(target, dtype=float))
            if insertion is not None:
                approach = self._reach(start, insertion[0], rng)
                if approach is not None:
                    return np.concatenate([approach, insertion[1:]])
        return super().plan(obstacles, start, target, rng)

    def insertion(self, start: np.ndarray, target: np.ndarray) -> np.ndarray | None:
        """Clear configurations (k, n_joints) from the pre-insertion one to the end of the insertion, ``SHORT`` of
        the target, each ``INSERT_STEP`` metres apart along the approach axis, the hand at the first of
        ``PITCHES`` that clears them all; or None. The end is solved first from seeds around ``start`` turned to
        face the target; each point back is seeded by the one after it."""
        way = approach_axis(target)
        end = target - SHORT * way
        seeds = np.repeat(np.asarray(start, dtype=float)[None], 4, axis=0)
        seeds[:, 0] = np.arctan2(target[1], target[0])
        seeds[1:, 5] += np.array([-1.0, 0.6, 1.2])  # the hand's pitch: turned up from pointing down
        fixed = np.random.default_rng(0).uniform(self.checker.lower, self.checker.upper, (EXTRA_SEEDS, len(start)))
        seeds = np.concatenate([seeds, fixed])
        steps = int(np.ceil(STANDOFF / INSERT_STEP))
        for pitch in PITCHES:
            axis = hand_axis(target, pitch)
            solved = self.hand.solve(end, axis, seeds)
            solved = solved[~np.isnan(solved).any(axis=1)]
            for goal in solved[np.argsort(np.linalg.norm(solved - start, axis=1))]:
                path = self._line(goal, end, way, axis, steps)
                if path is not None:
                    return path
        return None

    def _line(self, goal: np.ndarray, end: np.ndarray, way: np.ndarray, axis: np.ndarray,
              steps: int) -> np.ndarray | None:
        """The insertion ending at ``goal`` (the hand at ``end``), solved back point by point, if all clear."""
        points = [goal]
        for k in range(1, steps + 1):
            q = self.hand.solve(end - way * (STANDOFF * k / steps), axis, points[-1][None])[0]
            if np.isnan(q).any():
                return None
            points.append(q)
        path = np.array(points[::-1])
        clear = self.checker.free(path[:1]).all() and all(self._clear(q) for q in JointPath(path).points)
        return path if clear else None

    def _clear(self, q: np.ndarray) -> bool:
        return self.checker.clearance(q) >= INSERT_MARGIN and self.checker.model.self_collision() is None

    def _reach(self, start: np.ndarray, goal: np.ndarray, rng: np.random.Generator) -> np.ndarray | None:
        """The planner's path from ``start`` to the one configuration ``goal``, or None."""
        if _edge_free(self.checker, start, goal, RESOLUTION):
            return np.array([start, goal])
        path = rrt_connect(self.checker, start, goal[None], rng)
        return None if path is None else shortcut(self.checker, path, rng)
