"""Actions as bins: each entry of a ``Box(-1, 1)`` action takes one of ``n`` values evenly spaced from -1 to 1, and
the policy picks one per entry from a categorical distribution (a ``MultiDiscrete`` space).

A student imitating a teacher by regression learns the mean of what the teacher does in states it cannot tell
apart. Where the teacher turns hard left in some of them and hard right in others (the way around an obstacle
depends on the map), the mean is not turning at all, and a deterministic student stands still for good
(docs/learning.md, "Why the first students stood still"). Over bins the student learns how likely each command is,
and its deterministic action is the likeliest bin of each entry: one of the teacher's modes, never their average.
PPO fine-tunes such a policy as it does any ``MultiDiscrete`` one.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch as th
from gymnasium import spaces


def bin_values(bins: int) -> np.ndarray:
    """The ``bins`` values an entry takes, evenly from -1 to 1."""
    return np.linspace(-1.0, 1.0, bins)


def binned_space(space: spaces.Box, bins: int) -> spaces.MultiDiscrete:
    """The bins of a ``Box(-1, 1)`` action space.

    Raises:
        ValueError: ``space`` is not a one-dimensional box from -1 to 1.
    """
    if not (isinstance(space, spaces.Box) and len(space.shape) == 1 and np.all(space.low == -1.0)
            and np.all(space.high == 1.0)):
        raise ValueError(f"action_bins needs a Box(-1, 1, (n,)) action space, got {space}")
    return spaces.MultiDiscrete(np.full(space.shape[0], bins))


def decode(indices: Any, bins: int) -> np.ndarray:
    """The actions (float32) of bin ``indices`` (one action or a batch of them)."""
    return bin_values(bins)[np.asarray(indices, dtype=int)].astype(np.float32)


def soft_targets(actions: th.Tensor, bins: int) -> th.Tensor:
    """(batch, entries, bins) the two bins either side of each action entry, weighted by nearness (sums to 1): a
    label between two bins is learnt as a mix of them, not rounded."""
    position = (th.clamp(actions, -1.0, 1.0) + 1.0) * 0.5 * (bins - 1)
    low = th.clamp(position.floor().long(), 0, bins - 2)
    upper = position - low
    target = th.zeros(*actions.shape, bins)
    target.scatter_(-1, low.unsqueeze(-1), (1.0 - upper).unsqueeze(-1))
    target.scatter_add_(-1, (low + 1).unsqueeze(-1), upper.unsqueeze(-1))
    return target


class BinnedActions(gym.ActionWrapper):
    """The wrapped env's ``Box(-1, 1, (n,))`` actions as ``MultiDiscrete([bins] * n)``."""

    def __init__(self, env: gym.Env, bins: int) -> None:
        super().__init__(env)
        self.bins = bins
        self.action_space = binned_space(env.action_space, bins)

    def action(self, action: Any) -> np.ndarray:
        return decode(action, self.bins)
