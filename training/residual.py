"""A residual policy on a base controller: the env's action is ``clip(pursuit(obs) + policy action, -1, 1)``.

A simple controller (the pursuit) already does much of the task; the policy learns the correction: where the
pursuit cuts a corner into an obstacle, overshoots, stops short of the target or sits in a local minimum.
Training wraps each env in :class:`SubgoalResidual`; a loaded agent adds the same pursuit term in
``Agent.predict``, so it acts on plain env observations. The pursuit of each env (:func:`subgoal_pursuit`):

* ClutterNav-v0: :class:`~clutter_gym.training.baselines.PotentialFieldNavigator` on the ``goal``, reading the
  env's LIDAR: sensor-only, no map (``gain``: its turn gain, angular command per radian of heading error);
* ClutterReach-v0 (map-based, ``subgoal_lookahead > 0``): ``clip(gain * subgoal, -1, 1)``, every joint driven
  towards the joint-space subgoal on a path planned over the known layout, at a speed proportional to its offset
  (``gain``: actions per radian);
* ClutterFly-v0 (map-based, ``subgoal_lookahead > 0``): :class:`~clutter_gym.training.baselines.CascadedFlyer`
  on the subgoal, a flight stack's position controller (``gain``: its position gain, commanded m/s per metre of
  offset).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

Pursuit = Callable[[dict[str, np.ndarray]], np.ndarray]
#: The envs with a pursuit of the subgoal (map-based), and ClutterNav-v0's on the goal (sensor-only).
PURSUIT_ENVS = ("ClutterReach-v0", "ClutterFly-v0")
FIELD_ENVS = ("ClutterNav-v0",)


def subgoal_pursuit(env_id: str, gain: float, env: gym.Env | None = None) -> Pursuit:
    """The pursuit of ``env_id`` with ``gain`` (> 0): action(s) for one observation or a batch. ClutterNav-v0's
    reads the LIDAR of ``env`` (an env made with the run's settings), which it then needs.

    Raises:
        ValueError: ``env_id`` has no pursuit, or ClutterNav-v0 without an env.
    """
    from clutter_gym import TRAIN_IDS

    env_id = TRAIN_IDS.get(env_id, env_id)  # a *Train-v0 id is its env with the shipped settings
    if env_id == "ClutterNav-v0":
        if env is None:
            raise ValueError("ClutterNav-v0's potential field needs the env, for its LIDAR's beam angles and range")
        return _batched(_field(env, gain))
    if env_id == "ClutterReach-v0":
        return lambda obs: np.clip(gain * np.asarray(obs["subgoal"], dtype=np.float32), -1.0, 1.0)
    if env_id == "ClutterFly-v0":
        from clutter_gym.training.baselines import CascadedFlyer

        return CascadedFlyer.nominal("subgoal", position_gain=gain)
    raise ValueError(f"a residual policy needs an env with a pursuit, one of {FIELD_ENVS + PURSUIT_ENVS}; "
                     f"got {env_id!r}")


def _field(env: gym.Env, gain: float) -> Pursuit:
    from clutter_gym.training.baselines import PotentialFieldNavigator

    if "lidar" not in env.observation_space.spaces:
        raise ValueError("a residual on ClutterNav-v0's potential field needs 'lidar' in sensors")
    field = PotentialFieldNavigator.for_env(env)
    field.turn_gain = gain
    return field


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


class SubgoalResidual(gym.Wrapper):
    """Turns the wrapped env's actions into residuals on its pursuit (same spaces).

    Args:
        env: a ClutterNav env with a LIDAR, or a ClutterReach or ClutterFly env made with ``subgoal_lookahead > 0``.
        gain: the pursuit's gain (> 0; see :func:`subgoal_pursuit`).
    """

    def __init__(self, env: gym.Env, gain: float) -> None:
        from clutter_gym import TRAIN_IDS

        space = env.observation_space
        env_id = TRAIN_IDS.get(env.spec.id, env.spec.id) if env.spec else type(env.unwrapped).__name__
        if env_id in PURSUIT_ENVS and (not isinstance(space, gym.spaces.Dict) or "subgoal" not in space.spaces):
            raise ValueError("a residual on the subgoal needs an env with a 'subgoal' observation "
                             f"({' or '.join(PURSUIT_ENVS)} with subgoal_lookahead > 0)")
        super().__init__(env)
        self.gain = gain
        self.pursuit = subgoal_pursuit(env_id, gain, env)
        self._obs: dict[str, np.ndarray] | None = None

    def reset(self, **kwargs: Any) -> tuple[Any, dict]:
        obs, info = self.env.reset(**kwargs)
        self._obs = obs
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        obs, reward, terminated, truncated, info = self.env.step(residual_action(self._obs, action, self.pursuit))
        self._obs = obs
        return obs, reward, terminated, truncated, info
