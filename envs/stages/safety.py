"""The collision monitor as a stage: each command is slowed by what the latest delivered reading of the monitor's
sensor allows, and the base spun free when it stays pinned (:class:`clutter_gym.robots.safety.SafetyFilter`),
before the action noise."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clutter_gym.datatypes import Obstacle
from clutter_gym.robots.safety import SafetyFilter
from clutter_gym.stages.base import Stage

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv


class SafetyMonitor(Stage):
    """Runs ``safety`` on the readings of its sensor (``safety.sensor``, one of the env's sensors)."""

    def __init__(self, safety: SafetyFilter) -> None:
        self.safety = safety
        self._scale = 1.0

    def bind(self, env: ClutterEnv) -> None:
        """Raises:
            ValueError: the env has no sensor of that name (the message lists the sensors there are)."""
        names = [s.name for s in env.sensors]
        if self.safety.sensor not in names:
            raise ValueError(f"the safety filter reads the {self.safety.sensor!r} sensor; the env's sensors are "
                             f"{names}")
        self._index = names.index(self.safety.sensor)
        self._readings = env.timed_sensors.readings  # filled at every observation, the reset's too

    def episode_start(self, obstacles: Sequence[Obstacle], bodies: Sequence[int], rng: np.random.Generator) -> bool:
        self.safety.reset()
        return True

    def actuate(self, command: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        applied, self._scale = self.safety.filter(command, self._readings[self._index])
        return applied

    def step_info(self, info: dict[str, Any]) -> None:
        info["safety_scale"] = self._scale
        info["safety_recovery"] = self.safety.recovering
