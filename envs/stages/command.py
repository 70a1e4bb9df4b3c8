"""Commands an env's actions map onto, as stages (the reward and the monitor see the mapped command)."""

from __future__ import annotations

import numpy as np

from clutter_gym.stages.base import Stage


class ForwardOnly(Stage):
    """A base that drives forwards only: the forward action (entry 0) -1..1 means stand..full speed; the other
    entries pass unchanged."""

    def command(self, action: np.ndarray) -> np.ndarray:
        out = action.copy()
        out[0] = 0.5 * (action[0] + 1.0)
        return out
