"""A residual policy on a base controller: the env's action is ``clip(pursuit(obs) + policy action, -1, 1)``, or
on ClutterFly-v1 with ``residual_space="velocity"`` the flyer's inner loops flying its commanded velocity plus
the policy's offset (:func:`residual_map`).

A simple controller (the pursuit) already does much of the task; the policy learns the correction: where the
pursuit cuts a corner into an obstacle, overshoots, stops short of the target or sits in a local minimum.
Training wraps each env in :class:`SubgoalResidual`; a loaded agent adds the same pursuit term in
``Agent.predict``, so it acts on plain env observations. The pursuit of each env (:func:`subgoal_pursuit`):

* ClutterNav-v1: :class:`~clutter_gym.training.baselines.PotentialFieldNavigator` on the ``goal``, reading the
  env's LIDAR: sensor-only, no map (``gain``: its turn gain, angular command per radian of heading error);
* ClutterReach-v1 (map-based, ``subgoal_lookahead > 0``): ``clip(gain * subgoal, -1, 1)``, every joint driven
  towards the joint-space subgoal on a path planned over the known layout, at a speed proportional to its offset
  (``gain``: actions per radian); without a subgoal, :class:`~clutter_gym.training.baselines.ProximityFieldReacher`
  on the target, reading the arm's proximity readings: sensor-only (``gain``: its attraction, 1/s);
* ClutterFly-v1: :class:`~clutter_gym.training.baselines.CascadedFlyer`, a flight stack's position controller
  (``gain``: its position gain, commanded m/s per metre of offset), on the subgoal (map-based, with
  ``subgoal_lookahead > 0``) or, without one, straight at the goal: sensor-only, it sees no obstacle, and the
  policy's LIDAR or camera is what steers around them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from clutter_gym.training.hand_controller import HandController
from clutter_gym.util.checks import is_number

Pursuit = Callable[[dict[str, np.ndarray]], np.ndarray]
#: The envs with a pursuit of the subgoal (map-based), and those with a base controller on the goal (sensor-only).
PURSUIT_ENVS = ("ClutterReach-v1", "ClutterFly-v1")
MAPLESS_ENVS = ("ClutterNav-v1", "ClutterReach-v1", "ClutterFly-v1")
#: What a residual policy's action adds to (:func:`residual_map`).
RESIDUAL_SPACES = ("action", "velocity", "waypoint")
#: Turn gain of ClutterNav-v1's potential field when a policy picks its waypoint (its own default).
TURN_GAIN = 1.5
#: What the entries -1..1 of a waypoint a policy picks (``residual_space="waypoint"``) span: ClutterNav-v1's bearing
#: and ClutterFly-v1's azimuth and elevation (body frame), radians; ClutterReach-v1's hand displacement (metres) and
#: pitch (radians about its middle; :mod:`clutter_gym.training.hand_controller`).
WAYPOINT_SCALES = {"ClutterNav-v1": (math.pi,), "ClutterFly-v1": (math.pi, math.pi / 2),
                   "ClutterReach-v1": HandController.waypoint_scales}
#: Yaw rate per radian between the nose and the velocity commanded, 1/s, of the velocity residual's flyer.
FACING_GAIN = 2.0
#: The gains of ClutterFly-v1's flyer a run may set (``residual_base``), each in (0, :data:`MAX_BASE_GAIN`]; its
#: position gain is ``residual_gain``.
FLYER_GAINS = ("velocity_gain", "max_speed", "max_accel", "attitude_gain")
MAX_BASE_GAIN = 100.0


def subgoal_pursuit(env_id: str, gain: float, env: gym.Env | None = None, mapless: bool = False,
                   space: str = "action", base: dict[str, float] | None = None) -> Pursuit:
    """The pursuit of ``env_id`` with ``gain`` (> 0): action(s) for one observation or a batch; ``mapless``: the
    sensor-only base on the goal instead of the subgoal (ClutterNav-v1 has only that one); ``space="velocity"``
    (ClutterFly-v1): the flyer that turns its nose towards the velocity it flies (:func:`residual_map`); ``base``:
    ClutterFly-v1's flyer gains other than its defaults (:func:`check_residual_base`).
    ClutterNav-v1's and mapless ClutterReach-v1's read the LIDAR or the proximity readings of ``env`` (an env made
    with the run's settings), which they then need.

    Raises:
        ValueError: ``env_id`` has no such pursuit, a base that reads the env without one, a bad ``space``
            (:func:`check_residual_space`) or ``base`` (:func:`check_residual_base`).
    """
    from clutter_gym import TRAIN_IDS

    env_id = TRAIN_IDS.get(env_id, env_id)  # a *Train-v1 id is its env with the shipped settings
    check_residual_space(env_id, space)
    check_residual_base(env_id, base or {})
    if env_id == "ClutterNav-v1":
        if env is None:
            raise ValueError("ClutterNav-v1's potential field needs the env, for its LIDAR's beam angles and range")
        if space == "waypoint":
            return _field(env, gain or TURN_GAIN)
        return _batched(_field(env, gain))
    if env_id == "ClutterReach-v1" and space == "waypoint":
        if env is None:
            raise ValueError("ClutterReach-v1's hand controller needs the env, for its arm and joint speeds")
        return HandController.for_env(env)
    if env_id == "ClutterReach-v1" and not mapless:
        return lambda obs: np.clip(gain * np.asarray(obs["subgoal"], dtype=np.float32), -1.0, 1.0)
    if env_id == "ClutterReach-v1":
        from clutter_gym.training.baselines import ProximityFieldReacher

        if env is None:
            raise ValueError("ClutterReach-v1's proximity field needs the env, for its control mode and readings")
        return ProximityFieldReacher.for_env(env, attraction=gain)
    if env_id == "ClutterFly-v1" and space == "waypoint":
        from clutter_gym.training.field_flyer import FieldFlyer

        if env is None:
            raise ValueError("ClutterFly-v1's field flyer needs the env, for its LIDAR's beams and range")
        return FieldFlyer.for_env(env)
    if env_id == "ClutterFly-v1":
        from clutter_gym.training.baselines import CascadedFlyer

        facing = FACING_GAIN if space == "velocity" else 0.0
        return CascadedFlyer.nominal("goal" if mapless else "subgoal", position_gain=gain, yaw_gain=facing,
                                     **(base or {}))
    known = sorted(set(MAPLESS_ENVS + PURSUIT_ENVS))
    raise ValueError(f"a residual policy needs an env with a pursuit, one of {known}; got {env_id!r}")


def check_residual_space(env_id: str, space: str) -> None:
    """Raises a named ValueError unless ``space`` is one of :data:`RESIDUAL_SPACES` that ``env_id`` has."""
    if space not in RESIDUAL_SPACES:
        raise ValueError(f"residual_space must be one of {RESIDUAL_SPACES}, got {space!r}")
    if space == "velocity" and env_id != "ClutterFly-v1":
        raise ValueError(f"residual_space 'velocity' is ClutterFly-v1's (a residual on its flyer's velocity "
                         f"command), got {env_id!r}")
    if space == "waypoint" and env_id not in WAYPOINT_SCALES:
        raise ValueError(f"residual_space 'waypoint' is {', '.join(WAYPOINT_SCALES)}'s (where their base "
                         f"controllers steer for), got {env_id!r}")


def check_residual_base(env_id: str, base: dict[str, float]) -> None:
    """Raises a named ValueError unless ``base`` sets only gains of ClutterFly-v1's flyer (:data:`FLYER_GAINS`),
    each a number in (0, :data:`MAX_BASE_GAIN`]."""
    if not isinstance(base, dict):
        raise ValueError(f"residual_base must be a mapping of {FLYER_GAINS} to numbers, got {base!r}")
    if not base:
        return
    if env_id != "ClutterFly-v1":
        raise ValueError(f"residual_base sets the gains of ClutterFly-v1's flyer, got env {env_id!r}")
    for key, value in base.items():
        if key not in FLYER_GAINS:
            raise ValueError(f"residual_base.{key} is not a gain of the flyer; it has {FLYER_GAINS}")
        if not (is_number(value) and 0.0 < value <= MAX_BASE_GAIN):
            raise ValueError(f"residual_base.{key} must be a number in (0, {MAX_BASE_GAIN}], got {value!r}")


def _field(env: gym.Env, gain: float) -> Pursuit:
    from clutter_gym.training.baselines import PotentialFieldNavigator

    if "lidar" not in env.observation_space.spaces:
        raise ValueError("a residual on ClutterNav-v1's potential field needs 'lidar' in sensors")
    field = PotentialFieldNavigator.for_env(env)
    field.turn_gain = gain
    return field


def _rows(obs: dict[str, np.ndarray], action: Any, act: Callable[[dict, np.ndarray], np.ndarray]) -> np.ndarray:
    """``act(obs, action)`` for one observation, or row by row for a batch."""
    action = np.asarray(action, dtype=float)
    if action.ndim == 1:
        return act(obs, action)
    return np.stack([act({key: value[i] for key, value in obs.items()}, action[i]) for i in range(len(action))])


def _batched(pursuit: Pursuit) -> Pursuit:
    """``pursuit`` of one observation, applied row by row to a batch."""
    def act(obs: dict[str, np.ndarray]) -> np.ndarray:
        if np.ndim(obs["goal"]) == 1:
            return pursuit(obs)
        return np.stack([pursuit({key: value[i] for key, value in obs.items()}) for i in range(len(obs["goal"]))])
    return act


def residual_action(obs: dict[str, np.ndarray], action: np.ndarray, pursuit: Pursuit) -> np.ndarray:
    """The env action for the policy's residual ``action`` at raw observation ``obs``."""
    return np.clip(pursuit(obs) + action, -1.0, 1.0).astype(np.float32)


def residual_map(pursuit: Pursuit, space: str = "action") -> Callable[[dict[str, np.ndarray], Any], np.ndarray]:
    """``(raw observation, policy action) -> env action`` of a residual policy on ``pursuit`` (one or a batch),
    from :func:`subgoal_pursuit` with the same ``space``: ``"action"``, the policy's action adds to the pursuit's
    (:func:`residual_action`); ``"velocity"`` (ClutterFly-v1), it adds to the velocity the pursuit's
    :class:`~clutter_gym.training.baselines.CascadedFlyer` commands, in units of its top speed along body x, y, z,
    and the sum, capped at that speed, goes to the flyer's inner loops, which also turn the nose towards it
    (``yaw_gain`` :data:`FACING_GAIN`): the policy steers, the flyer flies, and the LIDAR and the camera look where
    the drone goes. A zero action is the pursuit's own action either way. ``"waypoint"``: the policy picks where to
    go and the base controller how: on ClutterNav-v1 its (1,) action is the bearing of the point to steer for, in
    units of pi, and the :class:`~clutter_gym.training.baselines.PotentialFieldNavigator` steers for it past the
    obstacles its LIDAR sees; on ClutterFly-v1, an azimuth and elevation the field flyer flies; on ClutterReach-v1,
    the hand's displacement and pitch, which the :class:`~clutter_gym.training.hand_controller.HandController`
    turns into joint velocities.
    """
    if space == "action":
        return lambda obs, action: residual_action(obs, action, pursuit)
    if space == "waypoint":
        scales = np.asarray(pursuit.waypoint_scales)

        def steer(obs: dict[str, np.ndarray], action: np.ndarray) -> np.ndarray:
            return pursuit.toward(obs, *(scales * np.clip(action, -1.0, 1.0)))
        return lambda obs, action: _rows(obs, action, steer)
    from clutter_gym.training.baselines import _capped

    def act(obs: dict[str, np.ndarray], action: np.ndarray) -> np.ndarray:
        offset = pursuit.max_speed * np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        return pursuit.track(_capped(pursuit.velocity(obs) + offset, pursuit.max_speed), obs)
    return act


def policy_action_space(env_action_space: gym.spaces.Box, space: str = "action",
                        env_id: str = "ClutterNav-v1") -> gym.spaces.Box:
    """The action space of a residual policy in ``space`` on ``env_id`` with ``env_action_space``."""
    if space == "velocity":
        return gym.spaces.Box(-1.0, 1.0, (3,), np.float32)
    if space == "waypoint":
        return gym.spaces.Box(-1.0, 1.0, (len(WAYPOINT_SCALES[env_id]),), np.float32)
    return env_action_space


class SubgoalResidual(gym.Wrapper):
    """Turns the wrapped env's actions into residuals on its pursuit (the same observations; the same actions, or
    ClutterFly's (3,) velocity offsets with ``space="velocity"``).

    Args:
        env: a ClutterNav env with a LIDAR, a ClutterReach env (on its subgoal when made with
            ``subgoal_lookahead > 0``, else on the target with ``observe_directions=True``), or a ClutterFly env
            (on its subgoal when it has one, else on the goal).
        gain: the pursuit's gain (> 0; see :func:`subgoal_pursuit`).
        space: what the residual adds to (:func:`residual_map`).
        base: ClutterFly-v1's flyer gains other than its defaults (:func:`check_residual_base`).
    """

    def __init__(self, env: gym.Env, gain: float, space: str = "action", base: dict[str, float] | None = None) -> None:
        from clutter_gym import TRAIN_IDS

        observations = env.observation_space
        env_id = TRAIN_IDS.get(env.spec.id, env.spec.id) if env.spec else type(env.unwrapped).__name__
        mapless = not isinstance(observations, gym.spaces.Dict) or "subgoal" not in observations.spaces
        if mapless and env_id not in MAPLESS_ENVS:
            raise ValueError("a residual on the subgoal needs an env with a 'subgoal' observation "
                             f"({' or '.join(PURSUIT_ENVS)} with subgoal_lookahead > 0)")
        super().__init__(env)
        self.gain = gain
        self.pursuit = subgoal_pursuit(env_id, gain, env, mapless=mapless, space=space, base=base)
        self.act = residual_map(self.pursuit, space)
        self.action_space = policy_action_space(env.action_space, space, env_id)
        self._obs: dict[str, np.ndarray] | None = None

    def reset(self, **kwargs: Any) -> tuple[Any, dict]:
        obs, info = self.env.reset(**kwargs)
        self._obs = obs
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        obs, reward, terminated, truncated, info = self.env.step(self.act(self._obs, action))
        self._obs = obs
        return obs, reward, terminated, truncated, info
