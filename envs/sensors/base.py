"""What every sensor provides to the env (a structural protocol; sensors do not inherit from it)."""

from __future__ import annotations

from typing import Protocol

import numpy as np
from gymnasium import spaces

from clutter_gym.robots.state import RobotState
from clutter_gym.sim import Sim


class Sensor(Protocol):
    """A clean read of the world in physical units, and its observation form.

    ``read`` never writes to the world. ``observe`` turns the physical reading into the (normalised, clipped)
    float32 value that lands in the observation dict under ``name``. ``info_key``, if set, names the ``info``
    entry that carries the physical reading.
    """

    name: str
    info_key: str | None
    observation_space: spaces.Box

    def reset(self, state: RobotState) -> None: ...

    def read(self, sim: Sim, state: RobotState) -> np.ndarray: ...

    def observe(self, reading: np.ndarray) -> np.ndarray: ...
