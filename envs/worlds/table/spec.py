"""The table world of ClutterReach-v1: its frame, the table, where targets are drawn for the arm, and what a
generated layout looks like.

Frame: the arm's base at the origin, the table top at z = -TABLE_GAP (the base stands on a mounting plate that
is not modelled, so the fixed base never "touches" the table), x forward, z up. Obstacles stand on the table
(``z`` = 0) or, for shelf boards, on the shelf's sides.
"""

from __future__ import annotations

from dataclasses import dataclass

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.checks import check_fraction, check_integer

TABLE_GAP = 0.005
TABLE = Obstacle("box", (1.6, 1.8, 0.05), (0.4, 0.0), 0.0, -0.05 - TABLE_GAP)


@dataclass(frozen=True)
class TableSpec:
    """Layout parameters.

    Attributes:
        n_obstacles: boxes and cylinders on the table, [0, 20].
        shelf: place a shelf (back, two sides, a middle board and a top) on the table.
        shelf_target_probability: chance that the target is inside the shelf, [0, 1].
        start_noise: uniform noise on each joint of the ready pose at the start, radians, [0, 0.5].
        target_clearance: least distance from the target to any obstacle, metres.
        movable_fraction: fraction of the boxes and cylinders (not the shelf) that are movable, in [0, 1].
        movable_density: kg/m^3 of movable clutter, that of packed groceries: a few hundred grams an object.
    """

    n_obstacles: int = 6
    shelf: bool = True
    shelf_target_probability: float = 0.3
    start_noise: float = 0.1
    target_clearance: float = 0.06
    movable_fraction: float = 0.0
    movable_density: float = 300.0

    def __post_init__(self) -> None:
        check_integer("n_obstacles", self.n_obstacles, 0, 20)
        if not 0.0 <= self.shelf_target_probability <= 1.0:
            raise ValueError(f"shelf_target_probability must be in [0, 1], got {self.shelf_target_probability!r}")
        if not 0.0 <= self.start_noise <= 0.5:
            raise ValueError(f"start_noise must be in [0, 0.5] rad, got {self.start_noise!r}")
        check_fraction("movable_obstacles", self.movable_fraction)
