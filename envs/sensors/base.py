"""What every sensor provides to the env (a structural protocol; sensors do not inherit from it).

A sensor is a clean read of the world, a chain of pure noise functions (``clutter_gym.noise``) and, outside the
sensor, a sample-and-hold plus delay line (:class:`clutter_gym.noise.timing.SampleHoldDelay`) that the env runs.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from gymnasium import spaces

from clutter_gym.robots.state import RobotState
from clutter_gym.sim import Sim


class Sensor(Protocol):
    """A noisy reading in physical units, and its observation form.

    Attributes:
        name: the sensor's name in ``sensors=(...)`` and in the noise profile's timing.
        spaces: observation keys this sensor fills, with their spaces.
        read_every_step: the sensor must be read every control step even while its output is held (state that
            integrates over time, like the IMU's finite difference).
    """

    name: str
    spaces: dict[str, spaces.Space]
    read_every_step: bool

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        """Start an episode: draw per-episode errors (biases, gains) from ``rng``."""

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> Any:
        """Clean reading plus noise, in physical units. Never writes to the world."""

    def observe(self, reading: Any) -> dict[str, np.ndarray]:
        """Observation entries (normalised/clipped as documented by the env) from a reading."""

    def info(self, reading: Any) -> dict[str, Any]:
        """``info`` entries that carry the physical reading (may be empty)."""
