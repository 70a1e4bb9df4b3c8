"""Per-episode safety and task statistics, gathered by a wrapper so training and evaluation count alike."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

#: Keys of ``info["episode_stats"]`` besides the per-term sums (``term_<name>``).
EPISODE_KEYS = ("return", "length", "success", "collision", "cost", "min_clearance")


class EpisodeStats(gym.Wrapper):
    """Adds ``info["episode_stats"]`` on the step that ends an episode.

    The entry holds ``return`` (sum of rewards), ``length`` (steps), ``success`` (``info["is_success"]`` at the
    end), ``collision`` (1.0 if any step had cost > 0, else 0.0), ``cost`` (sum of ``info["cost"]``),
    ``min_clearance`` (metres, smallest ``info["min_clearance"]`` seen, reset included) and ``term_<name>`` (sum of
    each reward term). Every value is a float, so rows of them go straight into a CSV or a mean.
    """

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        self._return, self._length, self._cost, self._collision = 0.0, 0, 0.0, False
        self._min_clearance = float(info.get("min_clearance", math.inf))
        self._terms: dict[str, float] = {}
        return obs, info

    def step(self, action: np.ndarray):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._return += float(reward)
        self._length += 1
        cost = float(info.get("cost", 0.0))
        self._cost += cost
        self._collision |= cost > 0.0
        self._min_clearance = min(self._min_clearance, float(info.get("min_clearance", math.inf)))
        for name, value in info.get("reward_terms", {}).items():
            self._terms[name] = self._terms.get(name, 0.0) + float(value)
        if terminated or truncated:
            info["episode_stats"] = {
                "return": self._return,
                "length": float(self._length),
                "success": float(bool(info.get("is_success", False))),
                "collision": float(self._collision),
                "cost": self._cost,
                "min_clearance": self._min_clearance,
                **{f"term_{name}": value for name, value in self._terms.items()},
            }
        return obs, reward, terminated, truncated, info
