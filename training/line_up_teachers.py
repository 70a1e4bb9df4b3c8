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


def _digest(scene: Any) -> bytes:
    return hashlib.sha256(repr(scene).encode()).digest()


class LineUpReacher(Teacher):
    """The subgoal pursuit of :class:`~clutter_gym.training.teachers.PlannerReacher` on the line-up planner's
    joint-space path: into a shelf's compartment, always the same way, where the planner's paths come in at a
    different hand orientation on every layout. One path per layout, from a random stream the layout itself seeds
    (as the env's subgoal path)."""

    LOOKAHEAD = 0.1  # radians of joint-space arc, the planner teacher's subgoal_lookahead

    def __init__(self, env: gym.Env) -> None:
        from clutter_gym.planning.line_up import LineUpPlanner

        self.env: Any = env.unwrapped
        self.planner = LineUpPlanner(arm=getattr(self.env, "robot").model)
        self.paths: dict[bytes, Any] = {}
        self.path: Any = None
        self._scene: Any = None

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        q = np.asarray(obs["joint_position"], dtype=float)
        if self.env.scene is not self._scene:
            self._scene, self.path = self.env.scene, self._plan(self.env.scene)
        if self.path is None:
            return np.zeros(len(q), dtype=np.float32)
        self.path.advance(q, window=max(2.0 * self.LOOKAHEAD, 0.3))
        subgoal = self.path.waypoint(self.LOOKAHEAD) - q
        return np.clip(REACH_PURSUIT_GAIN * subgoal, -1.0, 1.0).astype(np.float32)

    def _plan(self, scene: Any) -> Any:
        from clutter_gym.planning.path import JointPath

        digest = _digest(scene)
        if digest not in self.paths:
            rng = np.random.default_rng(int.from_bytes(digest[:8], "little"))
            self.paths[digest] = self.planner.plan(scene.obstacles, np.array(scene.start), np.array(scene.target), rng)
        path = self.paths[digest]
        return None if path is None else JointPath(path)


class LineUpHand(Teacher):
    """The line-up route in the hand controller's action space (the module's docstring), one route per layout."""

    def __init__(self, env: gym.Env) -> None:
        from clutter_gym.planning.line_up import LineUpPlanner

        self.env: Any = env.unwrapped
        self.planner = LineUpPlanner(arm=getattr(self.env, "robot").model)
        self.routes: dict[bytes, tuple[np.ndarray, float]] = {}
        self.route: tuple[np.ndarray, float] = (np.zeros((1, 3)), PITCH_MID)
        self._scene: Any = None

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        if self.env.scene is not self._scene:
            self._scene = self.env.scene
            digest = _digest(self._scene)
            if digest not in self.routes:
                self.routes[digest] = self.plan_route(self._scene)
            self.route = self.routes[digest]
        points, pitch = self.route
        hand = self.planner.hand.frames(np.asarray(obs["joint_position"], dtype=float))[0, :3, 3]
        aim = points[0]
        for k in range(len(points) - 1, 0, -1):  # the furthest leg the hand is on
            if tube_distance(hand, points[k - 1], points[k]) <= TUBE:
                aim = points[k]
                break
        offset = aim - hand
        move = offset / max(HAND_STEP, float(np.abs(offset).max()))
        return np.append(move, (pitch - PITCH_MID) / PITCH_SCALE).astype(np.float32)

    def plan_route(self, scene: Any) -> tuple[np.ndarray, float]:
        """The route's points (k, 3) and its pitch (radians below level) on layout ``scene``."""
        from clutter_gym.planning.hand_pose import approach_axis
        from clutter_gym.planning.line_up import PITCHES, SHORT, STANDOFF, covered

        target = np.asarray(scene.target, dtype=float)
        if not covered(target, scene.obstacles):
            over = np.array([target[0], target[1], max(target[2] + ABOVE, TRAVEL_HEIGHT)])
            return np.array([over, target]), math.pi / 2
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


def tube_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from ``point`` to the segment from ``a`` to ``b``."""
    ab = b - a
    t = float(np.clip((point - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0))
    return float(np.linalg.norm(point - (a + t * ab)))
