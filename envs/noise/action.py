"""Actuation noise: command latency and Gaussian noise on the normalised action."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from clutter_gym.noise.params import NoiseParams, param


@dataclass(frozen=True)
class ActionNoise(NoiseParams):
    """Attributes:
    latency_steps: control steps between the policy's action and its arrival at the motors.
    sigma: 1-sigma Gaussian noise added to each normalised action component (the action range is [-1, 1]);
        the result is clipped to the action space again.
    """

    section = "action"
    latency_steps: int = param(0, 0, 50, "control steps", "delay of each command", integer=True)
    sigma: float = param(0.0, 0.0, 1.0, "", "1-sigma noise on each normalised action component")


class ActionChannel:
    """The path of a command from the policy to the motors."""

    def __init__(self, params: ActionNoise, size: int) -> None:
        self.params = params
        self._line: deque[np.ndarray] = deque(maxlen=params.latency_steps + 1)
        self._size = size

    def reset(self) -> None:
        """Fill the delay line with zero commands (the robot starts at rest)."""
        self._line.clear()
        self._line.extend([np.zeros(self._size)] * (self.params.latency_steps + 1))

    def send(self, action: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The command that reaches the motors this step (unclipped; the caller clips)."""
        if self.params.is_clean:
            return action
        self._line.append(action)
        delivered = self._line[0]
        if self.params.sigma > 0.0:
            delivered = delivered + rng.normal(0.0, self.params.sigma, self._size)
        return delivered
