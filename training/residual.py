"""A residual policy on a subgoal pursuit: the env's action is ``clip(pursuit + policy action, -1, 1)``, where
``pursuit = clip(gain * subgoal, -1, 1)``.

With a map-based ClutterReach env (``subgoal_lookahead > 0``) the ``subgoal`` entry is the joint-space offset to
a point a little ahead on a planned path. Driving every joint towards it at a speed proportional to the offset
(pure pursuit) already follows the path; the policy learns the correction: where the pursuit cuts a corner into
an obstacle, or stops short of the target. Training wraps each env in :class:`SubgoalResidual`; a loaded
agent adds the same pursuit term in ``Agent.predict``, so it acts on plain env observations.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


def pursuit(obs: dict[str, np.ndarray], gain: float) -> np.ndarray:
    """``gain * obs["subgoal"]`` (one observation or a batch), in the action range."""
    return np.clip(gain * np.asarray(obs["subgoal"], dtype=np.float32), -1.0, 1.0)


def residual_action(obs: dict[str, np.ndarray], action: np.ndarray, gain: float) -> np.ndarray:
    """The env action for the policy's residual ``action`` at raw observation ``obs``."""
    return np.clip(pursuit(obs, gain) + action, -1.0, 1.0).astype(np.float32)


class SubgoalResidual(gym.Wrapper):
    """Turns the wrapped env's actions into residuals on the subgoal pursuit (same spaces).

    Args:
        env: an env whose observations have a ``subgoal`` entry shaped like its actions.
        gain: pursuit gain, actions per radian of subgoal offset (> 0).
    """

    def __init__(self, env: gym.Env, gain: float) -> None:
        space = env.observation_space
        if not isinstance(space, gym.spaces.Dict) or "subgoal" not in space.spaces:
            raise ValueError("a residual on the subgoal needs an env with a 'subgoal' observation "
                             "(ClutterReach-v0 with subgoal_lookahead > 0)")
        if space.spaces["subgoal"].shape != env.action_space.shape:
            raise ValueError(f"the subgoal {space.spaces['subgoal'].shape} and the actions {env.action_space.shape} "
                             "must have the same shape")
        super().__init__(env)
        self.gain = gain
        self._obs: dict[str, np.ndarray] | None = None

    def reset(self, **kwargs: Any) -> tuple[Any, dict]:
        obs, info = self.env.reset(**kwargs)
        self._obs = obs
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        obs, reward, terminated, truncated, info = self.env.step(residual_action(self._obs, action, self.gain))
        self._obs = obs
        return obs, reward, terminated, truncated, info
