"""Plain helpers shared by test modules in several folders: ``from helpers import empty_scene``.

Importable because pyproject.toml puts ``tests`` on pytest's ``pythonpath``. Fixtures live in conftest.py instead,
which pytest loads by itself and which is never imported.
"""

from __future__ import annotations

CHASSIS_RADIUS = 0.17  # diffbot.urdf: the chassis cylinder encloses every other link seen from above
SHELF_SEED = 1_000_000  # the first ClutterReach evaluation layout: its target is inside the shelf, no straight line
# reaches it


def empty_scene(start=(0.0, 0.0, 0.0), goal=(2.5, 2.5), obstacles=()) -> dict:
    """A ClutterNav scene in the reset-options format: no obstacles unless given."""
    return {"obstacles": list(obstacles), "start": list(start), "goal": list(goal)}
