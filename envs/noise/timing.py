"""Sensor timing: update rate (sample-and-hold) and latency (a delay line in control steps)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from clutter_gym.noise.params import NoiseParams, param


@dataclass(frozen=True)
class SensorTiming(NoiseParams):
    """When a sensor's readings reach the policy.

    Attributes:
        rate_hz: the sensor's update rate; 0 means every control step. Between updates the last reading is held.
            Each episode starts at a random phase of the sensor's period.
        latency_steps: control steps between a reading and its arrival in the observation.
    """

    section = "timing"
    rate_hz: float = param(0.0, 0.0, 10000.0, "Hz", "sensor update rate (0 = every control step)")
    latency_steps: int = param(0, 0, 50, "control steps", "delay of each reading", integer=True)


class SampleHoldDelay:
    """Sample-and-hold at ``rate_hz`` followed by a ``latency_steps`` delay line, ticking once per control step.

    Args:
        timing: rate and latency.
        control_dt: control period, seconds.
    """

    def __init__(self, timing: SensorTiming, control_dt: float) -> None:
        self.timing = timing
        self._period = 0.0 if timing.rate_hz == 0.0 else 1.0 / timing.rate_hz
        self._dt = control_dt
        self._line: deque[Any] = deque(maxlen=timing.latency_steps + 1)
        self._since_update = 0.0

    def reset(self, rng: np.random.Generator) -> None:
        """Empty the line and draw this episode's phase (nothing is drawn when the sensor runs every step)."""
        self._line.clear()
        if self._period > self._dt:
            self._since_update = float(rng.uniform(0.0, self._period))

    def due(self) -> bool:
        """Advance one control step; True when the sensor takes a new reading in it (always on the first)."""
        if not self._line or self._period <= self._dt:
            return True  # the first reading of an episode, or a sensor at least as fast as the control loop
        self._since_update += self._dt
        if self._since_update + 1e-9 >= self._period:
            self._since_update -= self._period
            return True
        return False

    def push(self, reading: Any | None) -> Any:
        """Record this step's reading (None = held) and return the one that arrives now.

        The first reading of an episode fills the whole line, so the first observations are not blank.
        """
        if reading is None:
            reading = self._line[-1]
        elif not self._line:
            self._line.extend([reading] * self._line.maxlen)
        self._line.append(reading)
        return self._line[0]
