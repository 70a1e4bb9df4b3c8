"""Put scenes into a Sim by moving pooled static bodies: no URDF reload, no resetSimulation on reset.

Bodies are pooled by exact shape (shape, size to 0.1 mm). A scene takes what the pool has and creates only
shapes it has never seen (cheap ``createMultiBody`` of one primitive); unused bodies are parked under the floor,
where static-static pairs are never tested by Bullet and no ray or robot reaches them. Generated layouts draw
sizes from a 5 cm grid, so the pool stops growing after a few hundred resets.
"""

from __future__ import annotations

from collections import defaultdict

from clutter_gym.sim import Sim
from clutter_gym.transforms import yaw_quat
from clutter_gym.worlds.scene import Obstacle

PARK_POSITION = (0.0, 0.0, -10.0)
_COLOURS = {"box": (0.62, 0.52, 0.40, 1.0), "cylinder": (0.45, 0.55, 0.45, 1.0), "wall": (0.35, 0.35, 0.38, 1.0)}


def _key(o: Obstacle) -> tuple:
    return (o.shape, *(round(v, 4) for v in o.size))


class ObstaclePool:
    """Static bodies for obstacles (reused across resets) and the four arena walls (built once)."""

    def __init__(self, sim: Sim, arena_size: float, wall_height: float = 0.5, wall_thickness: float = 0.1) -> None:
        self._sim = sim
        self._free: dict[tuple, list[int]] = defaultdict(list)
        self._active: list[tuple[tuple, int]] = []
        self.walls = self._build_walls(arena_size, wall_height, wall_thickness)

    def _build_walls(self, arena: float, height: float, thick: float) -> tuple[Obstacle, ...]:
        half, span = 0.5 * arena, arena + 2 * thick
        walls = (
            Obstacle("box", (span, thick, height), (0.0, half + 0.5 * thick)),
            Obstacle("box", (span, thick, height), (0.0, -half - 0.5 * thick)),
            Obstacle("box", (thick, span, height), (half + 0.5 * thick, 0.0)),
            Obstacle("box", (thick, span, height), (-half - 0.5 * thick, 0.0)),
        )
        self.wall_bodies = []
        for w in walls:
            body = self._sim.add_static_box([0.5 * s for s in w.size], _COLOURS["wall"])
            self._sim.move_static(body, (*w.position, 0.5 * w.size[2]), yaw_quat(0.0))
            self.wall_bodies.append(body)
        return walls

    @property
    def size(self) -> int:
        """Obstacle bodies created so far (active and parked)."""
        return len(self._active) + sum(len(v) for v in self._free.values())

    def _create(self, o: Obstacle) -> int:
        if o.shape == "box":
            return self._sim.add_static_box([0.5 * s for s in o.size], _COLOURS["box"])
        return self._sim.add_static_cylinder(o.radius, o.size[2], _COLOURS["cylinder"])

    def place(self, obstacles: tuple[Obstacle, ...]) -> list[int]:
        """Show exactly ``obstacles`` (in order) and park the bodies they no longer need; returns body ids."""
        released = {body for _, body in self._active}
        for key, body in self._active:
            self._free[key].append(body)
        self._active = []
        bodies = []
        for o in obstacles:
            key = _key(o)
            body = self._free[key].pop() if self._free[key] else self._create(o)
            self._sim.move_static(body, (*o.position, 0.5 * o.size[2]), yaw_quat(o.yaw))
            self._active.append((key, body))
            bodies.append(body)
        for body in released.difference(bodies):
            self._sim.move_static(body, PARK_POSITION, (0.0, 0.0, 0.0, 1.0))
        return bodies
