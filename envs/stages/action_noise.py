"""The noise profile's action channel as a stage: latency and Gaussian noise on the command, then clipped to the
action space (an env whose profile's action section is clean has no such stage)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.noise.action import ActionChannel, ActionNoise
from clutter_gym.stages.base import Stage

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv


class ActionNoiseStage(Stage):
    """Sends each command through an :class:`ActionChannel` of ``params``."""

    def __init__(self, params: ActionNoise) -> None:
        self.params = params

    def bind(self, env: ClutterEnv) -> None:
        space = env.robot.action_space
        self._channel = ActionChannel(self.params, space.shape[0])
        self._low, self._high = space.low.astype(np.float64), space.high.astype(np.float64)

    def episode_start(self, obstacles: Sequence[Obstacle], bodies: Sequence[int], rng: np.random.Generator) -> bool:
        self._channel.reset()
        return True

    def actuate(self, command: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.minimum(np.maximum(self._channel.send(command, rng), self._low), self._high)
