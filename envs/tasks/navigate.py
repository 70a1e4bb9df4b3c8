"""Reach a goal point on the floor without touching anything: reward terms, termination, goal observation.

The task reads only ground truth (robot state, collision report, the clipped action), never noisy
observations, and never calls pybullet.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from gymnasium import spaces

from clutter_gym.collision import CollisionReport
from clutter_gym.robots.state import RobotState

MAX_TILT_COS = 0.5  # the base z axis more than 60 degrees from vertical counts as flipped


@dataclass(frozen=True)
class NavRewardWeights:
    """Weights of the reward terms (all >= 0; the sign of each term is fixed by its meaning).

    Attributes:
        progress: per metre the goal distance shrinks in a step (negative when it grows).
        success: once, on reaching the goal.
        contact: per step with any robot/obstacle contact.
        clearance: per step, scaled by ``(margin - clearance) / margin`` when clearance < margin.
        control: per step, times the squared norm of the clipped action.
        time: per step.
    """

    progress: float = 10.0
    success: float = 10.0
    contact: float = 1.0
    clearance: float = 0.5
    control: float = 0.01
    time: float = 0.01

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not (math.isfinite(value) and 0.0 <= value <= 1e4):
                raise ValueError(f"reward weight {name} must be in [0, 1e4], got {value!r}")


@dataclass(frozen=True, slots=True)
class StepOutcome:
    """Reward, its signed terms, and the episode-ending flags of one step."""

    reward: float
    terms: dict[str, float]
    terminated: bool
    is_success: bool
    cost: float


class NavigateTask:
    """Drive the base frame origin to within ``success_radius`` of the goal.

    Args:
        weights: reward term weights.
        success_radius: metres, in (0, 2].
        clearance_margin: clearance below which the clearance term applies, metres, in [0, 1].
        terminate_on_collision: end the episode (terminated) on the first contact.
        max_goal_distance: upper bound of the distance observation (the arena diagonal), metres.
    """

    name = "goal"

    def __init__(
        self,
        weights: NavRewardWeights,
        success_radius: float,
        clearance_margin: float,
        terminate_on_collision: bool,
        max_goal_distance: float,
    ) -> None:
        if not (math.isfinite(success_radius) and 0.0 < success_radius <= 2.0):
            raise ValueError(f"success_radius must be in (0, 2] metres, got {success_radius!r}")
        if not (math.isfinite(clearance_margin) and 0.0 <= clearance_margin <= 1.0):
            raise ValueError(f"clearance_margin must be in [0, 1] metres, got {clearance_margin!r}")
        self.weights = weights
        self.success_radius = success_radius
        self.clearance_margin = clearance_margin
        self.terminate_on_collision = bool(terminate_on_collision)
        low = np.array([0.0, -1.0, -1.0], dtype=np.float32)
        high = np.array([max_goal_distance, 1.0, 1.0], dtype=np.float32)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        self._max_goal_distance = float(high[0])
        self._goal = np.zeros(2)
        self._previous_distance = 0.0

    def reset(self, goal: tuple[float, float], state: RobotState) -> None:
        self._goal = (float(goal[0]), float(goal[1]))
        self._previous_distance = self._distance(state)

    def _distance(self, state: RobotState) -> float:
        return float(math.hypot(self._goal[0] - state.position[0], self._goal[1] - state.position[1]))

    def observe(self, state: RobotState) -> np.ndarray:
        """(distance m, sin bearing, cos bearing); bearing is the goal direction in the robot frame, CCW from +x."""
        dx, dy = self._goal[0] - state.position[0], self._goal[1] - state.position[1]
        bearing = math.atan2(dy, dx) - state.yaw
        distance = min(math.hypot(dx, dy), self._max_goal_distance)
        return np.array([distance, math.sin(bearing), math.cos(bearing)], dtype=np.float32)

    def evaluate(self, state: RobotState, report: CollisionReport, action: np.ndarray) -> StepOutcome:
        """Reward terms and termination after a step, from ground truth only."""
        w = self.weights
        distance = self._distance(state)
        success = distance <= self.success_radius
        shortfall = max(0.0, self.clearance_margin - report.min_clearance)
        terms = {
            "progress": w.progress * (self._previous_distance - distance),
            "success": w.success if success else 0.0,
            "contact": -w.contact if report.in_contact else 0.0,
            "clearance": -w.clearance * min(1.0, shortfall / self.clearance_margin) if self.clearance_margin else 0.0,
            "control": -w.control * float(action @ action),
            "time": -w.time,
        }
        self._previous_distance = distance
        flipped = state.rotation[2, 2] < MAX_TILT_COS
        terminated = success or flipped or (self.terminate_on_collision and report.in_contact)
        return StepOutcome(sum(terms.values()), terms, terminated, success, 1.0 if report.in_contact else 0.0)
