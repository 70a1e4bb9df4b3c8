"""ClutterReach-v1's ``"line-up"`` teachers: a target under a shelf's board is reached the same way on every layout,
the hand lined up in front of it and then straight in (:mod:`clutter_gym.planning.line_up`).

:class:`LineUpReacher` answers in joint velocities, pursuing the line-up planner's joint-space path.
:class:`LineUpHand` answers in the hand controller's space (``residual_space="waypoint"``:
:mod:`clutter_gym.training.hand_controller`): a displacement towards the next point of a short route and the
route's pitch. The route of a target in the open: over it, above the clutter, then down onto it with the hand
pointing down; of a covered target: above the point in front of it, down to that point, then in, at the pitch the
line-up planner found clear. Which leg the hand is on is read from where the hand is (within a tube round the leg),
not remembered, so the label at a state the student strayed to is the way back onto the route.
"""

from __future__ import annotations

import hashlib
import math
from abc import abstractmethod
from typing import Any

import gymnasium as gym
import numpy as np

from clutter_gym.training.hand_controller import HAND_STEP, PITCH_MID, PITCH_SCALE
from clutter_gym.training.teachers import REACH_PURSUIT_GAIN, Teacher

#: Height (m above the table) the hand travels at between legs: over the tallest clutter (0.35 m) with the arm's
#: links to spare.
TRAVEL_HEIGHT = 0.45
#: How far above a target in the open the hand starts down, metres.
ABOVE = 0.1
#: Radius of the tube round a leg within which the hand is on it, metres.
TUBE = 0.03


class _PerLayout(Teacher):
    """A teacher that plans once per layout (:meth:`plan_layout`, cached by the layout's digest) and, from the first
    call of each episode, acts on the plan of the layout the env is on (:meth:`start`)."""

    def __init__(self, env: gym.Env) -> None:
        from clutter_gym.planning.line_up import LineUpPlanner

        self.env: Any = env.unwrapped
        self.planner = LineUpPlanner(arm=getattr(self.env, "robot").model)
        self.plans: dict[bytes, Any] = {}
        self._started = False

    def reset(self) -> None:
        self._started = False

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        if not self._started:
            scene = self.env.scene
            digest = hashlib.sha256(repr(scene).encode()).digest()
            if digest not in self.plans:
                self.plans[digest] = self.plan_layout(scene, np.random.default_rng(int.from_bytes(digest[:8],
                                                                                                   "little")))
            self.start(self.plans[digest])
            self._started = True
        return self.act(obs)

    @abstractmethod
    def plan_layout(self, scene: Any, rng: np.random.Generator) -> Any:
        """The plan of one layout, from a random stream the layout itself seeds."""

    @abstractmethod
    def start(self, plan: Any) -> None:
        """An episode on the layout of ``plan`` begins."""

    @abstractmethod
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The label at ``obs``."""


class LineUpReacher(_PerLayout):
    """The subgoal pursuit of :class:`~clutter_gym.training.teachers.PlannerReacher` on the line-up planner's
    joint-space path: into a shelf's compartment, always the same way, where the planner's paths come in at a
    different hand orientation on every layout."""

    LOOKAHEAD = 0.1  # radians of joint-space arc, the planner teacher's subgoal_lookahead

    def plan_layout(self, scene: Any, rng: np.random.Generator) -> np.ndarray | None:
        return self.planner.plan(scene.obstacles, np.array(scene.start), np.array(scene.target), rng)

    def start(self, plan: np.ndarray | None) -> None:
        from clutter_gym.planning.path import JointPath

        self.path = None if plan is None else JointPath(plan)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        q = np.asarray(obs["joint_position"], dtype=float)
        if self.path is None:
            return np.zeros(len(q), dtype=np.float32)
        self.path.advance(q, window=max(2.0 * self.LOOKAHEAD, 0.3))
        subgoal = self.path.waypoint(self.LOOKAHEAD) - q
        return np.clip(REACH_PURSUIT_GAIN * subgoal, -1.0, 1.0).astype(np.float32)


class LineUpHand(_PerLayout):
    """The line-up route in the hand controller's action space (the module's docstring), one route per layout."""

    def plan_layout(self, scene: Any, rng: np.random.Generator) -> tuple[np.ndarray, float]:
        """The route's points (k, 3) and its pitch (radians below level) on layout ``scene``."""
        from clutter_gym.planning.hand_pose import approach_axis
        from clutter_gym.planning.line_up import PITCHES, SHORT, STANDOFF, covered

        target = np.asarray(scene.target, dtype=float)
        if not covered(target, scene.obstacles):
            return over_route(target), math.pi / 2
        self.planner.checker.set_obstacles(scene.obstacles)
        insertion = self.planner.insertion(np.array(scene.start), target)
        pitch = PITCHES[-1]
        if insertion is not None:
            axis = self.planner.hand.frames(insertion[-1])[0, :3, 2]
            pitch = math.asin(float(np.clip(-axis[2], -1.0, 1.0)))
        way = approach_axis(target)
        end = target - SHORT * way
        front = end - STANDOFF * way
        over = np.array([front[0], front[1], max(front[2], TRAVEL_HEIGHT)])
        return np.array([over, front, end]), pitch

    def start(self, plan: tuple[np.ndarray, float]) -> None:
        self.route = plan

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        hand = self.planner.hand.frames(np.asarray(obs["joint_position"], dtype=float))[0, :3, 3]
        return route_action(hand, *self.route)


def over_route(target: np.ndarray) -> np.ndarray:
    """The route (2, 3) onto a target in the open: over it, above the clutter, then down."""
    return np.array([[target[0], target[1], max(target[2] + ABOVE, TRAVEL_HEIGHT)], target])


def route_action(hand: np.ndarray, points: np.ndarray, pitch: float) -> np.ndarray:
    """The hand controller's action (4,) taking the hand at ``hand`` along the route ``points`` (k, 3) at ``pitch``
    (radians below level): towards the end of the furthest leg whose tube holds the hand, else towards the first
    point; at full speed along the largest axis until it is within a step."""
    aim = points[0]
    for k in range(len(points) - 1, 0, -1):
        if tube_distance(hand, points[k - 1], points[k]) <= TUBE:
            aim = points[k]
            break
    offset = aim - hand
    move = offset / max(HAND_STEP, float(np.abs(offset).max()))
    return np.append(move, (pitch - PITCH_MID) / PITCH_SCALE).astype(np.float32)


def tube_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from ``point`` to the segment from ``a`` to ``b``."""
    ab = b - a
    t = float(np.clip((point - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0))
    return float(np.linalg.norm(point - (a + t * ab)))
