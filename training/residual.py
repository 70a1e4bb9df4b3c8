"""A residual policy on a subgoal pursuit: the env's action is ``clip(pursuit(obs) + policy action, -1, 1)``.

A map-based env (``subgoal_lookahead > 0``) tells the policy the ``subgoal``, a point a little ahead on a path
planned over the known layout. A simple controller steering for it (the pursuit) already follows the path; the
policy learns the correction: where the pursuit cuts a corner into an obstacle, overshoots, or stops short of the
target. Training wraps each env in :class:`SubgoalResidual`; a loaded agent adds the same pursuit term in
``Agent.predict``, so it acts on plain env observations. The pursuit of each env (:func:`subgoal_pursuit`):

* ClutterReach-v0: ``clip(gain * subgoal, -1, 1)``, every joint driven towards the joint-space subgoal at a
  speed proportional to its offset (``gain``: actions per radian);
* ClutterFly-v0: :class:`~clutter_gym.training.baselines.CascadedFlyer` on the subgoal, a flight stack's position
  controller (``gain``: its position gain, commanded m/s per metre of offset).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

Pursuit = Callable[[dict[str, np.ndarray]], np.ndarray]
#: The envs with a subgoal pursuit.
PURSUIT_ENVS = ("ClutterReach-v0", "ClutterFly-v0")


def subgoal_pursuit(env_id: str, gain: float) -> Pursuit:
    """The pursuit of ``env_id``'s subgoal with ``gain`` (> 0): action(s) for one observation or a batch.

    Raises:
        ValueError: ``env_id`` has no pursuit.
    """
    from clutter_gym import TRAIN_IDS

    env_id = TRAIN_IDS.get(env_id, env_id)  # a *Train-v0 id is its env with the shipped settings
    if env_id == "ClutterReach-v0":
        return lambda obs: np.clip(gain * np.asarray(obs["subgoal"], dtype=np.float32), -1.0, 1.0)
    if env_id == "ClutterFly-v0":
        from clutter_gym.training.baselines import CascadedFlyer

        return CascadedFlyer.nominal("subgoal", position_gain=gain)
    raise ValueError(f"a residual policy needs an env with a subgoal pursuit, one of {PURSUIT_ENVS}; got {env_id!r}")


def residual_action(obs: dict[str, np.ndarray], action: np.ndarray, pursuit: Pursuit) -> np.ndarray:
    """The env action for the policy's residual ``action`` at raw observation ``obs``."""
    return np.clip(pursuit(obs) + action, -1.0, 1.0).astype(np.float32)


class SubgoalResidual(gym.Wrapper):
    """Turns the wrapped env's actions into residuals on its subgoal pursuit (same spaces).

    Args:
        env: a ClutterReach or ClutterFly env made with ``subgoal_lookahead > 0``.
        gain: the pursuit's gain (> 0; see :func:`subgoal_pursuit`).
    """

    def __init__(self, env: gym.Env, gain: float) -> None:
        space = env.observation_space
        if not isinstance(space, gym.spaces.Dict) or "subgoal" not in space.spaces:
            raise ValueError("a residual on the subgoal needs an env with a 'subgoal' observation "
                             f"({' or '.join(PURSUIT_ENVS)} with subgoal_lookahead > 0)")
        super().__init__(env)
        self.gain = gain
        self.pursuit = subgoal_pursuit(env.spec.id if env.spec else type(env.unwrapped).__name__, gain)
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
