"""Reach: bring an arm's end effector to a target point among clutter without touching anything or itself."""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import CollisionReport, RobotState, StepOutcome
from clutter_gym.planning.path import JointPath
from clutter_gym.tasks.terms import check_weights, clearance_term, control_term, cost_by_cause
from clutter_gym.worlds.table.scene import ReachScene

if TYPE_CHECKING:
    from clutter_gym.planning.joint_space import ArmPlanner

#: Joint span (radians) the ``subgoal`` observation's box allows per joint: the widest Panda joint range.
SUBGOAL_BOUND = 6.0
#: Planned paths kept per env, by layout: an env that meets a layout again (training on a fixed set of layouts)
#: does not plan it again. Oldest first out.
PLAN_CACHE = 1024


@dataclass(frozen=True, kw_only=True)
class ReachRewardWeights:
    """Weights of the reward terms (all >= 0; the sign of each term is fixed by its meaning).

    Attributes:
        progress: per metre the end effector gets closer to the target in a step (negative when it recedes); with
            a subgoal path, per metre-equivalent of progress along the path (see ``ReachTask``).
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
        check_weights(self)


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
        subgoal_lookahead: radians of joint-space arc along the path planned on the known layout to the
            ``subgoal`` observation (0: no subgoal entry), [0, 3].
        make_planner: builds the planner of that path (called only when ``subgoal_lookahead > 0``).

    With a subgoal path, the progress term pays for progress along the path instead of the straight distance
    (backing out of a shelf is progress then), scaled so that the whole path pays what the straight distance
    would; a layout without a path keeps the straight distance.
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
        subgoal_lookahead: float = 0.0,
        make_planner: Callable[[], ArmPlanner] | None = None,
    ) -> None:
        if not (math.isfinite(success_radius) and 0.0 < success_radius <= 0.5):
            raise ValueError(f"success_radius must be in (0, 0.5] metres, got {success_radius!r}")
        if not (math.isfinite(clearance_margin) and 0.0 <= clearance_margin <= clearance_range):
            raise ValueError(f"clearance_margin must be in [0, clearance_range={clearance_range}] metres, "
                             f"got {clearance_margin!r}")
        if not (math.isfinite(subgoal_lookahead) and 0.0 <= subgoal_lookahead <= 3.0):
            raise ValueError(f"subgoal_lookahead must be in [0, 3] radians (0: no subgoal entry), "
                             f"got {subgoal_lookahead!r}")
        if subgoal_lookahead > 0.0 and make_planner is None:
            raise ValueError("subgoal_lookahead > 0 needs make_planner")
        self.weights = weights
        self.subgoal_lookahead = float(subgoal_lookahead)
        self.planner = make_planner() if make_planner is not None and self.subgoal_lookahead > 0.0 else None
        self.path: JointPath | None = None
        self._path_scale = 0.0  # metres of straight distance per radian of path; 0: progress on the straight line
        self._plans: dict[bytes, np.ndarray | None] = {}
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
        if self.planner is not None:
            self.spaces["subgoal"] = spaces.Box(-SUBGOAL_BOUND, SUBGOAL_BOUND, shape=(self.planner.n_joints,),
                                                dtype=np.float32)
        self._target = np.zeros(3)
        self._previous = 0.0
        self._followed: RobotState | None = None  # the state the path index was last moved to

    def marker_position(self, scene: ReachScene) -> tuple[float, float, float]:
        return scene.target

    def reset(self, scene: ReachScene, state: RobotState) -> None:
        self._target = np.array(scene.target, dtype=float)
        self._path_scale = 0.0
        if self.planner is not None:
            path = self._plan(self.planner, scene, state.joint_position)
            self.path = None if path is None else JointPath(path)
            if self.path is not None and self.path.length > 0.0:
                self._path_scale = self.distance(state) / self.path.length
        self._followed = None
        self._previous = self._to_go(state)

    def _to_go(self, state: RobotState) -> float:
        """What the progress term measures: metres from the end effector to the target, or, with a subgoal path,
        the joint-space arc left along it (plus the way back to it), scaled so the whole path is worth the
        straight distance it replaces."""
        if not self._path_scale:
            return self.distance(state)
        self._follow(state)
        path, q = self.path, state.joint_position
        assert path is not None, "reset sets a nonzero path scale only with a path"
        left = path.length - path.arc[path.index] + np.linalg.norm(q - path.points[path.index])
        return float(self._path_scale * left)

    def _plan(self, planner: ArmPlanner, scene: ReachScene, start: np.ndarray) -> np.ndarray | None:
        """The subgoal ``planner``'s path on ``scene`` from ``start``. Its random stream comes from the layout itself
        (the same scene and start give the same path), which also keys the cache."""
        digest = hashlib.sha256(repr((scene, start.tolist())).encode()).digest()
        if digest not in self._plans:
            if len(self._plans) >= PLAN_CACHE:
                del self._plans[next(iter(self._plans))]
            rng = np.random.default_rng(int.from_bytes(digest[:8], "little"))
            self._plans[digest] = planner.plan(scene.obstacles, start, self._target, rng)
        return self._plans[digest]

    def distance(self, state: RobotState) -> float:
        """Metres from the end effector to the target."""
        return float(np.linalg.norm(state.links.position[self._ee_row] - self._target))

    def observe(self, state: RobotState, report: CollisionReport) -> dict[str, np.ndarray]:
        """Target (world frame, m), per-link clearance (m, clipped to +-clearance_range) and the optional entries."""
        assert report.link_clearance is not None, "ReachTask needs a collision checker made with per_link=True"
        obs = {
            "target": self._target.astype(np.float32),
            "clearance": np.clip(report.link_clearance, -self._range, self._range).astype(np.float32),
        }
        if self.observe_directions:
            assert report.directions is not None, "ReachTask needs a collision checker made with per_link=True"
            obs["clearance_direction"] = report.directions.astype(np.float32)
        if self.observe_offset:
            obs["target_offset"] = (self._target - state.links.position[self._ee_row]).astype(np.float32)
        if self.planner is not None:
            obs["subgoal"] = self._subgoal(state)
        return obs

    def _follow(self, state: RobotState) -> None:
        """Move the path index to ``state``'s joints, once per state: :meth:`observe` and :meth:`evaluate` both
        read it, in whichever order they run (the index only moves forward, so a second move would skip ahead)."""
        if self.path is not None and state is not self._followed:
            self.path.advance(state.joint_position, window=max(2.0 * self.subgoal_lookahead, 0.3))
            self._followed = state

    def _subgoal(self, state: RobotState) -> np.ndarray:
        """The path point ``subgoal_lookahead`` ahead of the one nearest the joints, minus the joints; zero without a
        path."""
        q = state.joint_position
        if self.path is None:
            return np.zeros(len(q), dtype=np.float32)
        self._follow(state)
        offset = self.path.waypoint(self.subgoal_lookahead) - q
        return np.clip(offset, -SUBGOAL_BOUND, SUBGOAL_BOUND).astype(np.float32)

    def evaluate(self, state: RobotState, report: CollisionReport, action: np.ndarray) -> StepOutcome:
        """Reward terms and termination after a step, from ground truth only."""
        w = self.weights
        success = self.distance(state) <= self.success_radius
        to_go = self._to_go(state)
        self_contact = report.self_collision is not None
        terms = {
            "progress": w.progress * (self._previous - to_go),
            "success": w.success if success else 0.0,
            "contact": -w.contact if report.in_contact else 0.0,
            "self_contact": -w.self_contact if self_contact else 0.0,
            "clearance": clearance_term(w.clearance, self.clearance_margin, report.min_clearance),
            "tunneling": -w.tunneling * report.tunneling,
            "control": control_term(w.control, action),
        }
        self._previous = to_go
        costs = cost_by_cause(contact=report.in_contact, self_contact=self_contact, tunneling=report.tunneling > 0)
        terminated = success or (self.terminate_on_collision and any(costs.values()))
        return StepOutcome(sum(terms.values()), terms, terminated, success, costs)
