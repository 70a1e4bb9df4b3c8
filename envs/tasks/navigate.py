"""Reach a goal point on the floor without touching anything: reward terms, termination, goal observation.

The task reads only ground truth (robot state, collision report, the clipped action), never noisy
observations, and never calls pybullet.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import CollisionReport, RobotState, StepOutcome
from clutter_gym.tasks.terms import check_weights, clearance_term, control_term, cost_by_cause
from clutter_gym.worlds.floor.path import PathDistance
from clutter_gym.worlds.floor.scene import Scene
from clutter_gym.worlds.floor.spec import ClutterSpec

MAX_TILT_COS = 0.5  # the base z axis more than 60 degrees from vertical counts as flipped
#: Clearance beyond the footprint below which the subgoal's planner prefers other ways (its costmap inflation).
SUBGOAL_PLAN_MARGIN = 0.25


@dataclass(frozen=True, kw_only=True)
class NavRewardWeights:
    """Weights of the reward terms (all >= 0; the sign of each term is fixed by its meaning).

    Attributes:
        progress: per metre the path distance to the goal (around the clutter, ``worlds/floor/path.py``)
            shrinks in a step (negative when it grows).
        success: once, on reaching the goal.
        contact: per step with any robot/obstacle contact.
        clearance: per step, scaled by ``(margin - clearance) / margin`` when clearance < margin.
        control: per step, times the squared norm of the clipped action.
        time: per step.
        reverse: per m/s of backward speed, per step (0 by default; a training device against reversing blind
            into clutter, the habit that causes most crashes of a PPO agent on this task).
    """

    progress: float = 10.0
    success: float = 10.0
    contact: float = 1.0
    clearance: float = 0.5
    control: float = 0.01
    time: float = 0.01
    reverse: float = 0.0

    def __post_init__(self) -> None:
        check_weights(self)


class NavigateTask:
    """Drive the base frame origin to within ``success_radius`` of the goal.

    Progress is measured along the shortest path around the clutter, not the straight line, so that the reward
    has no local minima behind obstacles; the goal observation is the straight-line vector, as a real robot
    with a goal in odometry coordinates would have it.

    Args:
        weights: reward term weights.
        success_radius: metres, in (0, 2].
        clearance_margin: clearance below which the clearance term applies, metres, in [0, 1].
        terminate_on_collision: end the episode (terminated) on the first contact.
        max_goal_distance: upper bound of the distance observation (the arena diagonal), metres.
        spec: the arena's layout parameters (size and grid of the path-distance field).
        robot_radius: footprint radius for the path-distance field, metres.
        subgoal_lookahead: metres along the planned path on the known layout to the ``subgoal`` observation
            entry, in [0, max_goal_distance]; 0 leaves the entry out (the mapless default).
        observe_bearing: the goal entry also holds the bearing itself, as a fraction of pi in [-1, 1]. It jumps
            from 1 to -1 where the goal is straight behind, so a policy can turn the short way on both sides;
            from sin and cos alone any continuous policy's turn command passes through zero behind the robot.
    """

    def __init__(
        self,
        weights: NavRewardWeights,
        success_radius: float,
        clearance_margin: float,
        terminate_on_collision: bool,
        max_goal_distance: float,
        spec: ClutterSpec,
        robot_radius: float,
        subgoal_lookahead: float = 0.0,
        observe_bearing: bool = False,
    ) -> None:
        if not (math.isfinite(success_radius) and 0.0 < success_radius <= 2.0):
            raise ValueError(f"success_radius must be in (0, 2] metres, got {success_radius!r}")
        if not (math.isfinite(clearance_margin) and 0.0 <= clearance_margin <= 1.0):
            raise ValueError(f"clearance_margin must be in [0, 1] metres, got {clearance_margin!r}")
        if not (math.isfinite(subgoal_lookahead) and 0.0 <= subgoal_lookahead <= max_goal_distance):
            raise ValueError(f"subgoal_lookahead must be in [0, {max_goal_distance:.4g}] metres (0: no subgoal "
                             f"entry), got {subgoal_lookahead!r}")
        self.weights = weights
        self.success_radius = success_radius
        self.clearance_margin = clearance_margin
        self.terminate_on_collision = bool(terminate_on_collision)
        low = np.array([0.0, -1.0, -1.0], dtype=np.float32)
        high = np.array([max_goal_distance, 1.0, 1.0], dtype=np.float32)
        self.observe_bearing = bool(observe_bearing)
        extra = 1 if self.observe_bearing else 0
        self.spaces = {"goal": spaces.Box(np.append(low, [-1.0] * extra).astype(np.float32),
                                          np.append(high, [1.0] * extra).astype(np.float32), dtype=np.float32)}
        self.subgoal_lookahead = float(subgoal_lookahead)
        if self.subgoal_lookahead > 0.0:
            sub_high = np.array([self.subgoal_lookahead, 1.0, 1.0], dtype=np.float32)
            self.spaces["subgoal"] = spaces.Box(low, sub_high, dtype=np.float32)
        self._max_goal_distance = float(high[0])
        self.spec, self.robot_radius = spec, robot_radius
        self._goal = (0.0, 0.0)
        self._path_distance: PathDistance | None = None
        self._previous_path = 0.0

    def marker_position(self, scene: Scene) -> tuple[float, float, float]:
        return (*scene.goal, 0.005)

    def reset(self, scene: Scene, state: RobotState) -> None:
        self._goal = (float(scene.goal[0]), float(scene.goal[1]))
        margin = SUBGOAL_PLAN_MARGIN if self.subgoal_lookahead > 0.0 else None
        self._path_distance = PathDistance(scene, self.spec, self.robot_radius, plan_margin=margin)
        self._previous_path = self.path_distance(state)

    @property
    def _field(self) -> PathDistance:
        """The episode's path-distance field, which :meth:`reset` makes from the scene."""
        if self._path_distance is None:
            raise RuntimeError("NavigateTask has no path-distance field before reset(scene, state)")
        return self._path_distance

    def path_distance(self, state: RobotState) -> float:
        """Metres to the goal along the shortest path the footprint fits through."""
        return self._field(float(state.position[0]), float(state.position[1]))

    def planned_path(self, point: tuple[float, float]) -> np.ndarray:
        """(k, 2) the subgoal planner's path from ``point`` to the goal, metres (needs ``subgoal_lookahead > 0``)."""
        return self._field.path(*point)

    def _distance(self, state: RobotState) -> float:
        return float(math.hypot(self._goal[0] - state.position[0], self._goal[1] - state.position[1]))

    def observe(self, state: RobotState, report: CollisionReport) -> dict[str, np.ndarray]:
        """``goal``: (distance m, sin bearing, cos bearing); bearing is the goal direction in the robot frame, CCW
        from +x. ``subgoal`` (when enabled): the same for the point ``subgoal_lookahead`` metres ahead on the
        planned path (the goal itself when nearer)."""
        x, y = float(state.position[0]), float(state.position[1])
        goal = polar(self._goal, x, y, state.yaw, self._max_goal_distance)
        if self.observe_bearing:
            goal = np.append(goal, np.float32(math.atan2(goal[1], goal[2]) / math.pi))
        obs = {"goal": goal}
        if self.subgoal_lookahead > 0.0:
            point = self._field.waypoint(x, y, lookahead=self.subgoal_lookahead)
            obs["subgoal"] = polar(point, x, y, state.yaw, self.subgoal_lookahead)
        return obs

    def evaluate(self, state: RobotState, report: CollisionReport, action: np.ndarray) -> StepOutcome:
        """Reward terms and termination after a step, from ground truth only."""
        w = self.weights
        distance = self._distance(state)
        path = self.path_distance(state)
        success = distance <= self.success_radius
        terms = {
            "progress": w.progress * (self._previous_path - path),
            "success": w.success if success else 0.0,
            "contact": -w.contact if report.in_contact else 0.0,
            "clearance": clearance_term(w.clearance, self.clearance_margin, report.min_clearance),
            "control": control_term(w.control, action),
            "time": -w.time,
        }
        if w.reverse:
            terms["reverse"] = -w.reverse * max(0.0, -_forward_speed(state))
        self._previous_path = path
        flipped = state.rotation[2, 2] < MAX_TILT_COS
        terminated = success or flipped or (self.terminate_on_collision and report.in_contact)
        return StepOutcome(sum(terms.values()), terms, terminated, success, cost_by_cause(contact=report.in_contact))


def _forward_speed(state: RobotState) -> float:
    """Speed along the base's heading, m/s (negative when driving backwards)."""
    vx, vy = state.linear_velocity[0], state.linear_velocity[1]
    return vx * math.cos(state.yaw) + vy * math.sin(state.yaw)


def polar(point: Sequence[float], x: float, y: float, yaw: float, max_distance: float) -> np.ndarray:
    """(distance, sin bearing, cos bearing) of ``point`` seen from a robot at (x, y) heading ``yaw``."""
    dx, dy = point[0] - x, point[1] - y
    bearing = math.atan2(dy, dx) - yaw
    return np.array([min(math.hypot(dx, dy), max_distance), math.sin(bearing), math.cos(bearing)], dtype=np.float32)
