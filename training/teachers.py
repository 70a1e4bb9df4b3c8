"""Privileged teachers: controllers that see what a student policy may not, whose actions label the states a student
visits (:mod:`clutter_gym.training.distill`).

Each env has the map-based planner reference of docs/baselines.md as its teacher (``"planner"``): it reads the
``subgoal`` entry, the point a fixed length ahead on a path planned over the known layout, which the env adds when
it is made with the teacher's :attr:`Teacher.env_kwargs` on top of the student's own. ClutterNav-v0 has a second
one, ``"seen-map"``: the same planner on a map of only the obstacles the LIDAR has hit so far in the episode (free
space elsewhere, as a robot's own map is), which a student with memory could in principle match; it measures how
much of the student-teacher gap the map explains (docs/learning.md, "How much of the teacher a student can see").

A teacher answers in the student's action space: the env's for ClutterNav-v0 and ClutterReach-v0; for
ClutterFly-v0, the velocity the flight controller's inner loops fly (:data:`clutter_gym.training.residual`'s
``"velocity"`` space with no base velocity), in units of the flyer's top speed.
:class:`TeacherLabels` runs the teacher inside the env's process, on the env's own state, and reports its action in
``info``; with probability :attr:`TeacherLabels.teacher_share` an episode is driven by the teacher instead of the
policy (DAgger's mixture).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import gymnasium as gym
import numpy as np

#: Each env's teachers, the first its default, and the env arguments each one reads on top of the student's.
TEACHERS: dict[str, dict[str, dict[str, Any]]] = {
    "ClutterNav-v0": {"planner": {"subgoal_lookahead": 0.5}, "seen-map": {"subgoal_lookahead": 0.5}},
    "ClutterReach-v0": {"planner": {"subgoal_lookahead": 0.1}},
    "ClutterFly-v0": {"planner": {"subgoal_lookahead": 0.5}},
}
#: ClutterReach-v0's pursuit gain on the subgoal (actions per radian), the map-based block's (ppo.yml).
REACH_PURSUIT_GAIN = 15.0


def check_teacher(env_id: str, name: str) -> None:
    """Raises a named ValueError unless ``name`` is a teacher of ``env_id``."""
    if env_id not in TEACHERS:
        raise ValueError(f"teacher: {env_id} has no teacher; the envs with one: {sorted(TEACHERS)}")
    if name not in TEACHERS[env_id]:
        raise ValueError(f"teacher.name must be one of {sorted(TEACHERS[env_id])} for {env_id}, got {name!r}")


class Teacher(ABC):
    """A controller on privileged observations; :meth:`reset` after every env reset, then one call per step."""

    def reset(self) -> None:
        """A new episode starts."""

    @abstractmethod
    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        """The action for the env's current state, in the student's action space."""


class PlannerNavigator(Teacher):
    """ClutterNav-v0's planner reference: the potential field steering for the subgoal on the known layout's
    planned path (:class:`~clutter_gym.training.baselines.PotentialFieldNavigator` with ``goal_key="subgoal"``)."""

    def __init__(self, env: gym.Env) -> None:
        from clutter_gym.training.baselines import PotentialFieldNavigator

        self.field = PotentialFieldNavigator.for_env(env, goal_key="subgoal")

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        return self.field(obs)


class SeenMapNavigator(PlannerNavigator):
    """The planner reference planning on the obstacles the LIDAR has hit so far this episode (every return is
    matched to the obstacle within 5 cm of it; the arena's walls are known, as its size is), free space elsewhere.
    Its plan is redone whenever a new obstacle is seen."""

    #: metres: a return this close to an obstacle's footprint is taken as that obstacle seen
    MATCH = 0.05

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.env = env.unwrapped
        lidar = next((s for s in self.env.sensors if s.name == "lidar"), None)
        if lidar is None or lidar.config.n_channels != 1:
            raise ValueError("the seen-map teacher needs a 2D LIDAR: 'lidar' in sensors and lidar_channels 1")
        self.angles, self.max_range = np.asarray(lidar.config.angles), float(lidar.config.max_range)
        self.lookahead = float(self.env.task.subgoal_lookahead)
        self.reset()

    def reset(self) -> None:
        self.seen: frozenset[int] = frozenset()
        self._planned: frozenset[int] | None = None
        self._path = None

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        from clutter_gym.tasks.navigate import SUBGOAL_PLAN_MARGIN, polar
        from clutter_gym.worlds.floor.path import PathDistance
        from clutter_gym.worlds.floor.scene import Scene

        env = self.env
        state = env.robot.state()
        x, y, yaw = float(state.position[0]), float(state.position[1]), state.yaw
        self.seen |= self._hit(np.asarray(info["lidar_ranges"], dtype=float), x, y, yaw)
        if self.seen != self._planned:
            scene = env.scene
            known = Scene(tuple(scene.obstacles[i] for i in sorted(self.seen)), scene.start, scene.goal)
            task = env.task
            self._path = PathDistance(known, task.spec, task.robot_radius, plan_margin=SUBGOAL_PLAN_MARGIN)
            self._planned = self.seen
        point = self._path.waypoint(x, y, lookahead=self.lookahead)
        return self.field({**obs, "subgoal": polar(point, x, y, yaw, self.lookahead)})

    def _hit(self, ranges: np.ndarray, x: float, y: float, yaw: float) -> frozenset[int]:
        """The obstacles within :attr:`MATCH` of a return of this scan."""
        obstacles = self.env.scene.obstacles
        hit = np.isfinite(ranges) & (ranges < self.max_range - 1e-3)
        if not hit.any() or not obstacles:
            return frozenset()
        angle = self.angles[hit] + yaw
        points = np.stack([x + ranges[hit] * np.cos(angle), y + ranges[hit] * np.sin(angle)], axis=1)
        gaps = np.stack([_footprint_distance(points, o) for o in obstacles], axis=1)
        nearest = gaps.argmin(axis=1)
        return frozenset(int(i) for i in nearest[gaps[np.arange(len(points)), nearest] < self.MATCH])


def _footprint_distance(points: np.ndarray, obstacle: Any) -> np.ndarray:
    """(m,) distance from each of ``points`` (m, 2) to ``obstacle``'s footprint, metres (0 inside)."""
    offset = points - np.asarray(obstacle.position[:2], dtype=float)
    if obstacle.shape == "cylinder":
        return np.maximum(np.linalg.norm(offset, axis=1) - obstacle.radius, 0.0)
    c, s = math.cos(obstacle.yaw), math.sin(obstacle.yaw)
    local = np.stack([c * offset[:, 0] + s * offset[:, 1], -s * offset[:, 0] + c * offset[:, 1]], axis=1)
    return np.linalg.norm(np.maximum(np.abs(local) - 0.5 * np.asarray(obstacle.size[:2]), 0.0), axis=1)


class PlannerReacher(Teacher):
    """ClutterReach-v0's planner reference: every joint driven towards the subgoal on the joint-space path planned
    over the known layout, ``clip(gain x subgoal)`` (the map-based block's pursuit)."""

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        return np.clip(REACH_PURSUIT_GAIN * np.asarray(obs["subgoal"], dtype=np.float32), -1.0, 1.0)


class PlannerFlyer(Teacher):
    """ClutterFly-v0's planner reference: the cascaded position controller's velocity towards the subgoal on the
    shortest path through the known layout, in units of its top speed (the student's velocity commands)."""

    def __init__(self, env: gym.Env) -> None:
        from clutter_gym.training.baselines import CascadedFlyer

        self.flyer = CascadedFlyer.nominal("subgoal")

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        return (self.flyer.velocity(obs) / self.flyer.max_speed).astype(np.float32)


def make_teacher(env_id: str, name: str, env: gym.Env) -> Teacher:
    """Teacher ``name`` of ``env_id`` on ``env`` (made with the student's and the teacher's env arguments).

    Raises:
        ValueError: no such teacher (:func:`check_teacher`).
    """
    check_teacher(env_id, name)
    if env_id == "ClutterNav-v0":
        return SeenMapNavigator(env) if name == "seen-map" else PlannerNavigator(env)
    if env_id == "ClutterReach-v0":
        return PlannerReacher()
    return PlannerFlyer(env)


class TeacherLabels(gym.Wrapper):
    """Adds the teacher's action for the state an action was taken in, ``info["teacher_action"]``, to every step;
    drives a share of the episodes with the teacher (``info["teacher_drove"]``).

    Which episodes the teacher drives is drawn from a generator of the wrapper's own, seeded from the first reset's
    seed, so the env's ``np_random`` (its layouts) is the same with the wrapper as without it.

    Args:
        env: the env, made with the student's and the teacher's arguments (and, on ClutterFly-v0, behind the
            velocity interface the student acts through).
        teacher: the teacher, answering in ``env``'s action space.
        teacher_share: the probability that an episode is driven by the teacher, in [0, 1].
    """

    def __init__(self, env: gym.Env, teacher: Teacher, teacher_share: float = 0.0) -> None:
        super().__init__(env)
        self.teacher, self.teacher_share = teacher, float(teacher_share)
        self._rng = np.random.default_rng(0)
        self._label: np.ndarray | None = None
        self._teacher_drives = False

    def set_teacher_share(self, share: float) -> None:
        """The probability that an episode starting from now on is driven by the teacher."""
        self.teacher_share = float(share)

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        if kwargs.get("seed") is not None:
            self._rng = np.random.default_rng(kwargs["seed"])
        obs, info = self.env.reset(**kwargs)
        self.teacher.reset()
        self._label = self.teacher(obs, info)
        self._teacher_drives = bool(self._rng.uniform() < self.teacher_share)
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._label is None:
            raise RuntimeError("call reset() before step()")
        label, drives = self._label, self._teacher_drives
        obs, reward, terminated, truncated, info = self.env.step(label if drives else action)
        info["teacher_action"], info["teacher_drove"] = label, drives
        self._label = self.teacher(obs, info)
        return obs, reward, terminated, truncated, info
