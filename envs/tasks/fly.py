"""Fly to a goal point through a cluttered volume without touching anything: reward terms, termination, goal
observation.

The task reads only ground truth (robot state, collision report, the clipped action), never noisy observations,
and never calls pybullet. Frames: world z up, metres; the body frame is the base link's (x forward, y left, z up).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import CollisionReport, RobotState, StepOutcome
from clutter_gym.tasks.terms import check_weights, clearance_term, control_term, cost_by_cause
from clutter_gym.worlds.volume.path import VolumePathDistance
from clutter_gym.worlds.volume.scene import VolumeScene, boundary_distance
from clutter_gym.worlds.volume.spec import VolumeSpec


@dataclass(frozen=True, kw_only=True)
class FlyRewardWeights:
    """Weights of the reward terms (all in [0, 1e4]; the sign of each term is fixed by its meaning).

    Attributes:
        progress: per metre the path distance to the goal (through the volume, ``worlds/volume/path.py``) shrinks
            in a step (negative when it grows).
        success: once, on reaching the goal.
        crash: once, on an episode-ending failure: leaving the volume, flipping, or a contact that ends the
            episode (``terminate_on_collision``).
        contact: per unsafe step: a contact, or a swept hit between two checks (tunneling).
        clearance: per step, scaled by ``(margin - clearance) / margin`` when clearance < margin.
        control: per step, times the squared distance of the clipped action from the hover action.
        attitude: per step, times ``1 - cos(tilt)`` (0 level, 1 on its side, 2 upside down).
        rate: per step, times the squared body rate, (rad/s)^2.
    """

    progress: float = 10.0
    success: float = 10.0
    crash: float = 10.0
    contact: float = 1.0
    clearance: float = 0.5
    control: float = 0.01
    attitude: float = 0.1
    rate: float = 0.01

    def __post_init__(self) -> None:
        check_weights(self)


class FlyTask:
    """Bring the base frame origin to within ``success_radius`` of the goal point.

    Progress follows the shortest path through the volume for a sphere of ``robot_radius`` (no local minima behind
    obstacles); the goal observation is the straight-line vector, as a drone given its goal in odometry coordinates
    would have it.

    Args:
        weights: reward term weights.
        spec: the volume (its size bounds the episode; its grid carries the path distance).
        robot_radius: bounding radius of the robot for the path distance, metres.
        success_radius: metres, in (0, 2].
        clearance_margin: clearance below which the clearance term applies, metres, in [0, 1].
        max_tilt: tilt of the body z axis from vertical beyond which the robot counts as flipped, radians, in
            (0, pi].
        terminate_on_collision: end the episode (terminated) on the first unsafe step (contact or tunneling).
        hover_action: the action that holds a level hover; the control term charges the distance from it.
        subgoal_lookahead: metres along the path behind the progress field to the ``subgoal`` observation
            (0: no such entry), in [0, volume diagonal].
    """

    def __init__(
        self,
        weights: FlyRewardWeights,
        spec: VolumeSpec,
        robot_radius: float,
        success_radius: float,
        clearance_margin: float,
        max_tilt: float,
        terminate_on_collision: bool,
        hover_action: np.ndarray | Sequence[float],
        subgoal_lookahead: float = 0.0,
    ) -> None:
        if not (math.isfinite(success_radius) and 0.0 < success_radius <= 2.0):
            raise ValueError(f"success_radius must be in (0, 2] metres, got {success_radius!r}")
        if not (math.isfinite(clearance_margin) and 0.0 <= clearance_margin <= 1.0):
            raise ValueError(f"clearance_margin must be in [0, 1] metres, got {clearance_margin!r}")
        if not (math.isfinite(max_tilt) and 0.0 < max_tilt <= math.pi):
            raise ValueError(f"max_tilt must be in (0, pi] radians, got {max_tilt!r}")
        diagonal = float(math.sqrt(sum(v * v for v in spec.size)))
        if not (math.isfinite(subgoal_lookahead) and 0.0 <= subgoal_lookahead <= diagonal):
            raise ValueError(f"subgoal_lookahead must be in [0, {diagonal:.4g}] metres (0: no subgoal entry), got "
                             f"{subgoal_lookahead!r}")
        self.weights = weights
        self.spec = spec
        self.robot_radius = float(robot_radius)
        self.success_radius = float(success_radius)
        self.clearance_margin = float(clearance_margin)
        self.terminate_on_collision = bool(terminate_on_collision)
        self._min_tilt_cos = math.cos(max_tilt)
        self._hover = np.asarray(hover_action, dtype=np.float64)
        self.max_goal_distance = d = diagonal
        low = np.array([-d, -d, -d, 0.0], dtype=np.float32)
        self.spaces = {"goal": spaces.Box(low, np.full(4, d, dtype=np.float32), dtype=np.float32)}
        self.subgoal_lookahead = float(subgoal_lookahead)
        if self.subgoal_lookahead > 0.0:
            self.spaces["subgoal"] = spaces.Box(-self.subgoal_lookahead, self.subgoal_lookahead, shape=(3,),
                                                dtype=np.float32)
        self._goal = np.zeros(3)
        self._path_distance: VolumePathDistance | None = None
        self._previous_path = 0.0

    def marker_position(self, scene: VolumeScene) -> tuple[float, float, float]:
        x, y, z = scene.goal
        return (float(x), float(y), float(z))

    def reset(self, scene: VolumeScene, state: RobotState) -> None:
        self._goal = np.array(scene.goal, dtype=np.float64)
        self._path_distance = VolumePathDistance(scene, self.spec, self.robot_radius)
        self._previous_path = self.path_distance(state)

    @property
    def _field(self) -> VolumePathDistance:
        """The episode's path-distance field, which :meth:`reset` makes from the scene."""
        if self._path_distance is None:
            raise RuntimeError("FlyTask has no path-distance field before reset(scene, state)")
        return self._path_distance

    def path_distance(self, state: RobotState) -> float:
        """Metres to the goal along the shortest path a sphere of ``robot_radius`` fits through."""
        p = state.position
        return self._field(float(p[0]), float(p[1]), float(p[2]))

    def planned_path(self, point: Sequence[float]) -> np.ndarray:
        """(k, 3) the path behind the progress field from ``point`` to the goal, metres."""
        return self._field.path(*point)

    def observe(self, state: RobotState, report: CollisionReport) -> dict[str, np.ndarray]:
        """``goal``: the goal minus the base origin in the body frame (x, y, z, m; each clipped to the volume's
        diagonal), then its length (m, clipped the same). ``subgoal`` (when enabled): the point
        ``subgoal_lookahead`` ahead on the path behind the progress field (the goal itself when nearer) minus the
        base origin, body frame, metres."""
        position = np.asarray(state.position)
        offset = state.rotation.T @ (self._goal - position)
        d = self.max_goal_distance
        out = np.empty(4, dtype=np.float32)
        out[:3] = np.clip(offset, -d, d)
        out[3] = min(float(np.linalg.norm(offset)), d)
        if self.subgoal_lookahead <= 0.0:
            return {"goal": out}
        point = self._field.waypoint(*position.tolist(), lookahead=self.subgoal_lookahead)
        sub = state.rotation.T @ (np.asarray(point) - position)
        bound = self.subgoal_lookahead
        return {"goal": out, "subgoal": np.clip(sub, -bound, bound).astype(np.float32)}

    def evaluate(self, state: RobotState, report: CollisionReport, action: np.ndarray) -> StepOutcome:
        """Reward terms and termination after a step, from ground truth only."""
        w = self.weights
        position = np.asarray(state.position)
        path = self.path_distance(state)
        success = float(np.linalg.norm(self._goal - position)) <= self.success_radius
        unsafe = report.in_contact or report.tunneling > 0
        outside = boundary_distance(position, self.spec) < 0.0  # through a wall, over the top or below the floor
        flipped = state.rotation[2, 2] < self._min_tilt_cos
        crashed = outside or flipped or (self.terminate_on_collision and unsafe)
        body_rate = state.rotation.T @ np.asarray(state.angular_velocity)
        terms = {
            "progress": w.progress * (self._previous_path - path),
            "success": w.success if success and not crashed else 0.0,
            "crash": -w.crash if crashed else 0.0,
            "contact": -w.contact if unsafe else 0.0,
            "clearance": clearance_term(w.clearance, self.clearance_margin, report.min_clearance),
            "control": control_term(w.control, action - self._hover),
            "attitude": -w.attitude * (1.0 - float(state.rotation[2, 2])),
            "rate": -w.rate * float(body_rate @ body_rate),
        }
        self._previous_path = path
        success = success and not crashed
        costs = cost_by_cause(contact=report.in_contact, tunneling=report.tunneling > 0)
        return StepOutcome(sum(terms.values()), terms, success or crashed, success, costs)
