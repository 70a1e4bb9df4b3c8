"""Per-episode dynamics randomisation: friction, restitution, masses and motor strength within ranges."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.noise.params import NoiseParams, param


@dataclass(frozen=True)
class DynamicsNoise(NoiseParams):
    """Scale factors are drawn uniformly in ``[1 - range, 1 + range]`` once per episode (all zero = nominal).

    Attributes:
        friction_range: scale of the robot's lateral friction coefficients (wheel grip).
        restitution_max: restitution of the robot's links, drawn in [0, restitution_max] (nominal is 0).
        mass_range: scale of every robot link's mass (inertia scales with it).
        motor_range: scale of the motors' torque limit.
    """

    section = "dynamics"
    friction_range: float = param(0.0, 0.0, 0.9, "", "relative friction spread")
    restitution_max: float = param(0.0, 0.0, 1.0, "", "largest restitution drawn")
    mass_range: float = param(0.0, 0.0, 0.9, "", "relative mass spread")
    motor_range: float = param(0.0, 0.0, 0.9, "", "relative torque-limit spread")


def sample_dynamics(rng: np.random.Generator, params: DynamicsNoise) -> DynamicsSample:
    """Draw one episode's dynamics (nothing is drawn for a parameter that is zero)."""

    def scale(spread: float) -> float:
        return 1.0 if spread == 0.0 else float(rng.uniform(1.0 - spread, 1.0 + spread))

    return DynamicsSample(
        friction_scale=scale(params.friction_range),
        restitution=0.0 if params.restitution_max == 0.0 else float(rng.uniform(0.0, params.restitution_max)),
        mass_scale=scale(params.mass_range),
        motor_scale=scale(params.motor_range),
    )
