"""Frame stacking, the policy's short memory: it sees its episode's last ``k`` observations, each entry concatenated
along its last axis, oldest first (zeros before the first observation of the episode).

Training wraps the normalised vector env in SB3's ``VecFrameStack``; an :class:`~clutter_gym.training.agent.Agent`
keeps the same stack, built by the same SB3 class, in its ``state``, so a loaded policy sees exactly what it was
trained on.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnv, VecFrameStack
from stable_baselines3.common.vec_env.stacked_observations import StackedObservations


def stack_frames(venv: VecEnv, n_stack: int) -> VecEnv:
    """``venv`` behind a stack of its last ``n_stack`` observations (``venv`` itself for 1)."""
    return VecFrameStack(venv, n_stack) if n_stack > 1 else venv


def frame_space(stacked: spaces.Space, n_stack: int) -> spaces.Space:
    """The space of one observation, from the space of a stack of ``n_stack`` of them."""
    if isinstance(stacked, spaces.Dict):
        return spaces.Dict({key: frame_space(sub, n_stack) for key, sub in stacked.spaces.items()})
    if n_stack == 1:
        return stacked
    n = stacked.shape[-1] // n_stack
    return spaces.Box(stacked.low[..., -n:], stacked.high[..., -n:], dtype=stacked.dtype)


def push_frame(obs, state: StackedObservations | None, n_stack: int, space: spaces.Space):
    """Add a batch of observations (leading batch axis) to the episode's stack; returns ``(stacked obs, state)``.

    ``state`` is None at the start of an episode: a new stack is made, zeros behind ``obs``. Every row of a batch
    starts its episode together.
    """
    batch = len(next(iter(obs.values()))) if isinstance(obs, dict) else len(obs)
    if state is None:
        state = StackedObservations(batch, n_stack, space)
        return state.reset(obs), state
    stacked, _ = state.update(obs, np.zeros(batch, dtype=bool), [{} for _ in range(batch)])
    return stacked, state
