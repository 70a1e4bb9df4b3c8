"""Sensor timing parameters: update rate and latency (``clutter_gym.sensors.timing`` runs them)."""

from __future__ import annotations

from dataclasses import dataclass

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
