"""Privileged teachers: controllers that see what a student policy may not, whose actions label the states a student
visits (:mod:`clutter_gym.training.distill`).

Each env has the map-based planner reference of docs/baselines.md as its teacher (``"planner"``): it reads the
``subgoal`` entry, the point a fixed length ahead on a path planned over the known layout, which the env adds when
it is made with the teacher's env arguments (:data:`TEACHERS`) on top of the student's own. ClutterNav-v1's
``"committed"`` is the same planner keeping the turn its robot has begun where both ways round are about as long
(:class:`PlannerNavigator`). ``"seen-map"`` and ``"in-range"`` (ClutterNav-v1, ClutterFly-v1) plan on only the
obstacles the LIDAR has hit this episode, or hits in its current scan (:mod:`clutter_gym.training.known_map`):
what a student with a memory, or without one, could in principle match. They measure how much of the
student-teacher gap the map explains (docs/learning.md, "How much of the teacher a student can see").
ClutterFly-v1's ``"taut"`` points at the farthest point of the planner's path in sight
(:mod:`clutter_gym.training.taut_path`), a label that does not turn with the drone's place in a grid cell.
ClutterReach-v1's ``"line-up"`` reaches into a shelf's compartment the same way on every layout
(:mod:`clutter_gym.training.line_up_teachers`), in joint velocities or, for a student acting through the hand
controller, in its space.

A teacher answers in the student's action space: the env's for ClutterNav-v1 and ClutterReach-v1; for
ClutterFly-v1, the velocity the flight controller's inner loops fly (:data:`clutter_gym.training.residual`'s
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
    "ClutterNav-v1": {"planner": {"subgoal_lookahead": 0.5}, "committed": {"subgoal_lookahead": 0.5},
                      "seen-map": {"subgoal_lookahead": 0.5}, "in-range": {"subgoal_lookahead": 0.5}},
    "ClutterReach-v1": {"planner": {"subgoal_lookahead": 0.1}, "line-up": {}},
    "ClutterFly-v1": {"planner": {"subgoal_lookahead": 0.5}, "taut": {"subgoal_lookahead": 0.5},
                      "seen-map": {"subgoal_lookahead": 0.5}, "in-range": {"subgoal_lookahead": 0.5}},
}
#: radians: how much shorter the other way round may be before ClutterNav-v1's committed teachers turn it
COMMIT = math.pi / 3
#: ClutterReach-v1's pursuit gain on the subgoal (actions per radian), the map-based block's (ppo.yml).
REACH_PURSUIT_GAIN = 15.0


def check_teacher(env_id: str, name: str, space: str = "action") -> None:
    """Raises a named ValueError unless ``name`` is a teacher of ``env_id`` that answers in the student's action
    ``space``: ClutterReach-v1's hand controller (``"waypoint"``) has only the ``line-up`` teacher."""
    if env_id not in TEACHERS:
        raise ValueError(f"teacher: {env_id} has no teacher; the envs with one: {sorted(TEACHERS)}")
    if name not in TEACHERS[env_id]:
        raise ValueError(f"teacher.name must be one of {sorted(TEACHERS[env_id])} for {env_id}, got {name!r}")
    if env_id == "ClutterReach-v1" and space == "waypoint" and name != "line-up":
        raise ValueError(f"residual_space waypoint on ClutterReach-v1 (the hand controller) needs teacher.name "
                         f"'line-up', the teacher that answers in the hand's space, got {name!r}")


class Teacher(ABC):
    """A controller on privileged observations; :meth:`reset` after every env reset, then one call per step."""

    def reset(self) -> None:
        """A new episode starts."""

    @abstractmethod
    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        """The action for the env's current state, in the student's action space."""


class PlannerNavigator(Teacher):
    """ClutterNav-v1's planner reference: the potential field steering for the subgoal on the known layout's
    planned path (:class:`~clutter_gym.training.baselines.PotentialFieldNavigator` with ``goal_key="subgoal"``).

    With ``commit`` > 0 (radians) it keeps turning the way the robot turns (its yaw rate, the ``velocity``
    entry) when the subgoal lies so far behind that the other way round is at most ``commit`` shorter: which way
    the path leaves is the map's, but which way a robot already turning keeps turning is something its student can
    see, so its labels stop flipping between hard left and hard right at the same view (docs/learning.md).
    """

    #: rad/s: a yaw rate below this is no turn to keep
    TURNING = 0.1

    def __init__(self, env: gym.Env, commit: float = 0.0, waypoint: bool = False) -> None:
        from clutter_gym.training.baselines import PotentialFieldNavigator

        self.field = PotentialFieldNavigator.for_env(env, goal_key="subgoal")
        self.commit, self.waypoint = commit, waypoint

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        return self._answer(obs)

    def _answer(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """For a student that picks its waypoint (``waypoint``), the subgoal's bearing in units of pi; else the
        field's action towards the subgoal."""
        if self.waypoint:
            return np.array([math.atan2(float(obs["subgoal"][1]), float(obs["subgoal"][2])) / math.pi], np.float32)
        return self._act(obs)

    def _act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        error, ahead = self.field.steer(obs)
        yaw_rate = float(obs["velocity"][1])
        if (self.commit and abs(yaw_rate) > self.TURNING and yaw_rate * error < 0.0
                and abs(error) > math.pi - 0.5 * self.commit):
            error -= math.copysign(2.0 * math.pi, error)  # the long way round, which it has begun
        return self.field.command(error, ahead)


class PlannerReacher(Teacher):
    """ClutterReach-v1's planner reference: every joint driven towards the subgoal on the joint-space path planned
    over the known layout, ``clip(gain x subgoal)`` (the map-based block's pursuit)."""

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        return np.clip(REACH_PURSUIT_GAIN * np.asarray(obs["subgoal"], dtype=np.float32), -1.0, 1.0)


def flyer_waypoint(subgoal: np.ndarray) -> np.ndarray:
    """A ClutterFly-v1 ``subgoal`` (x, y, z, body frame) as the waypoint a student picks: its azimuth and elevation
    in units of pi and pi / 2."""
    x, y, z = (float(v) for v in subgoal[:3])
    return np.array([math.atan2(y, x) / math.pi, math.atan2(z, math.hypot(x, y)) / (math.pi / 2)], dtype=np.float32)


class PlannerFlyer(Teacher):
    """ClutterFly-v1's planner reference: the cascaded position controller's velocity towards the subgoal on the
    shortest path through the known layout, in units of its top speed (the student's velocity commands); or, for a
    student that picks its waypoint (``waypoint``), the subgoal's azimuth and elevation in units of pi and pi / 2."""

    def __init__(self, env: gym.Env, waypoint: bool = False) -> None:
        from clutter_gym.training.baselines import CascadedFlyer

        self.flyer = CascadedFlyer.nominal("subgoal")
        self.waypoint = waypoint

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        if self.waypoint:
            return flyer_waypoint(obs["subgoal"])
        return (self.flyer.velocity(obs) / self.flyer.max_speed).astype(np.float32)


def make_teacher(env_id: str, name: str, env: gym.Env, space: str = "action") -> Teacher:
    """Teacher ``name`` of ``env_id`` on ``env`` (made with the student's and the teacher's env arguments),
    answering in the student's action ``space`` (:func:`clutter_gym.training.residual.residual_map`).

    Raises:
        ValueError: no such teacher, or none that answers in ``space`` (:func:`check_teacher`).
    """
    check_teacher(env_id, name, space)
    if name in ("seen-map", "in-range"):
        from clutter_gym.training.known_map import SeenMapFlyer, SeenMapNavigator

        keep = name == "seen-map"
        if env_id == "ClutterNav-v1":
            return SeenMapNavigator(env, COMMIT, keep, space == "waypoint")
        return SeenMapFlyer(env, keep, space == "waypoint")
    if env_id == "ClutterNav-v1":
        return PlannerNavigator(env, COMMIT if name == "committed" else 0.0, space == "waypoint")
    if env_id == "ClutterReach-v1" and name == "line-up":
        from clutter_gym.training.line_up_teachers import LineUpHand, LineUpReacher

        return LineUpHand(env) if space == "waypoint" else LineUpReacher(env)
    if env_id == "ClutterReach-v1":
        return PlannerReacher()
    if name == "taut":
        from clutter_gym.training.taut_path import TautFlyer

        return TautFlyer(env, space == "waypoint")
    return PlannerFlyer(env, space == "waypoint")


class TeacherLabels(gym.Wrapper):
    """Adds the teacher's action for the state an action was taken in, ``info["teacher_action"]``, to every step;
    drives a share of the episodes with the teacher (``info["teacher_drove"]``).

    Which episodes the teacher drives is drawn from a generator of the wrapper's own, seeded from the first reset's
    seed, so the env's ``np_random`` (its layouts) is the same with the wrapper as without it.

    Args:
        env: the env, made with the student's and the teacher's arguments (and, on ClutterFly-v1, behind the
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
