"""Reach: bring an arm's end effector to a target point among clutter without touching anything or itself."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from gymnasium import spaces

from clutter_gym.collision import CollisionReport
from clutter_gym.interfaces import StepOutcome
from clutter_gym.robots.state import RobotState
from clutter_gym.worlds.tabletop import ReachScene


@dataclass(frozen=True)
class ReachRewardWeights:
    """Weights of the reward terms (all >= 0; the sign of each term is fixed by its meaning).

    Attributes:
        progress: per metre the end effector gets closer to the target in a step (negative when it recedes).
        success: once, on reaching the target.
        contact: per step with any arm/obstacle contact.
        self_contact: per step with the arm in self-collision (a pair the ACM checks).
        clearance: per step, scaled by ``(margin - clearance) / margin`` when the arm's clearance < margin.
        tunneling: per swept-check hit the end-of-step check missed (a contact between two checks).
        control: per step, times the squared norm of the clipped action.
    """

    progress: float = 10.0
    success: float = 10.0
    contact: float = 1.0
    self_contact: float = 1.0
    clearance: float = 0.2
    tunneling: float = 1.0
    control: float = 0.005

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not (math.isfinite(value) and 0.0 <= value <= 1e4):
                raise ValueError(f"reward weight {name} must be in [0, 1e4], got {value!r}")


class ReachTask:
    """End effector within ``success_radius`` of the target ends the episode with success.

    Args:
        weights: reward term weights.
        ee_row: row of ``state.links`` holding the end-effector link.
        links: names of the arm links whose clearance is observed (the checker's moving links).
        success_radius: metres, in (0, 0.5].
        clearance_margin: clearance below which the clearance term applies, metres, in [0, clearance_range].
        clearance_range: clearances are observed up to this distance, metres.
        terminate_on_collision: end the episode (terminated) on the first environment or self contact.
        observe_directions: add the per-link unit vectors towards the nearest obstacle to the observation.
        observe_offset: add ``target_offset``, the target minus the end-effector position, to the observation.
    """

    def __init__(
        self,
        weights: ReachRewardWeights,
        ee_row: int,
        links: tuple[str, ...],
        success_radius: float,
        clearance_margin: float,
        clearance_range: float,
        terminate_on_collision: bool,
        observe_directions: bool,
        observe_offset: bool = False,
    ) -> None:
        if not (math.isfinite(success_radius) and 0.0 < success_radius <= 0.5):
            raise ValueError(f"success_radius must be in (0, 0.5] metres, got {success_radius!r}")
        if not (math.isfinite(clearance_margin) and 0.0 <= clearance_margin <= clearance_range):
            raise ValueError(f"clearance_margin must be in [0, clearance_range={clearance_range}] metres, "
                             f"got {clearance_margin!r}")
        self.weights = weights
        self.success_radius = success_radius
        self.clearance_margin = clearance_margin
        self.terminate_on_collision = bool(terminate_on_collision)
        self.observe_directions = bool(observe_directions)
        self.observe_offset = bool(observe_offset)
        self._ee_row = ee_row
        self._range = clearance_range
        n = len(links)
        self.spaces = {
            "target": spaces.Box(-1.5, 1.5, shape=(3,), dtype=np.float32),
            "clearance": spaces.Box(-clearance_range, clearance_range, shape=(n,), dtype=np.float32),
        }
        if self.observe_directions:
            self.spaces["clearance_direction"] = spaces.Box(-1.0, 1.0, shape=(n, 3), dtype=np.float32)
        if self.observe_offset:
            self.spaces["target_offset"] = spaces.Box(-3.0, 3.0, shape=(3,), dtype=np.float32)
        self._target = np.zeros(3)
        self._previous = 0.0

    def marker_position(self, scene: ReachScene) -> tuple[float, float, float]:
        return scene.target

    def reset(self, scene: ReachScene, state: RobotState) -> None:
        self._target = np.array(scene.target, dtype=float)
        self._previous = self.distance(state)

    def distance(self, state: RobotState) -> float:
        """Metres from the end effector to the target."""
        return float(np.linalg.norm(state.links.position[self._ee_row] - self._target))

    def observe(self, state: RobotState, report: CollisionReport) -> dict[str, np.ndarray]:
        """Target (world frame, m), per-link clearance (m, clipped to +-clearance_range) and the optional entries."""
        obs = {
            "target": self._target.astype(np.float32),
            "clearance": np.clip(report.link_clearance, -self._range, self._range).astype(np.float32),
        }
        if self.observe_directions:
            obs["clearance_direction"] = report.directions.astype(np.float32)
        if self.observe_offset:
            obs["target_offset"] = (self._target - state.links.position[self._ee_row]).astype(np.float32)
        return obs

    def evaluate(self, state: RobotState, report: CollisionReport, action: np.ndarray) -> StepOutcome:
        """Reward terms and termination after a step, from ground truth only."""
        w = self.weights
        distance = self.distance(state)
        success = distance <= self.success_radius
        shortfall = max(0.0, self.clearance_margin - report.min_clearance)
        self_contact = report.self_collision is not None
        terms = {
            "progress": w.progress * (self._previous - distance),
            "success": w.success if success else 0.0,
            "contact": -w.contact if report.in_contact else 0.0,
            "self_contact": -w.self_contact if self_contact else 0.0,
            "clearance": -w.clearance * min(1.0, shortfall / self.clearance_margin) if self.clearance_margin else 0.0,
            "tunneling": -w.tunneling * report.tunneling,
            "control": -w.control * float(action @ action),
        }
        self._previous = distance
        unsafe = report.in_contact or self_contact or report.tunneling > 0
        terminated = success or (self.terminate_on_collision and unsafe)
        return StepOutcome(sum(terms.values()), terms, terminated, success, 1.0 if unsafe else 0.0)
