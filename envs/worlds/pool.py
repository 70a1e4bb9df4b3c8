"""Put scenes into a Sim by moving pooled static bodies: no URDF reload, no resetSimulation on reset.

Bodies are pooled by exact shape (shape and size). A scene takes what the pool has and creates only the
shapes it lacks; bodies it does not need are parked under the floor, asleep and invisible (a camera frame
would otherwise pay for their triangles). Parked bodies are not free: Bullet visits every body each physics
tick, so the pool keeps at most ``max_parked`` of them and deletes the least recently used beyond that
(docs/design-notes.md#parked-bodies). Generated layouts draw their sizes from a few levels per range
(``ClutterSpec.size_levels``), so a small pool covers every layout and resets rarely create anything; user
scenes with new sizes create bodies as needed, a one-off cost per new shape.

Movable obstacles (those with a mass) are pooled apart from static ones: Bullet fixes whether a body is dynamic when
it is made. A parked movable body has mass 0, so it hangs where it is parked; placed, it gets its obstacle's mass and
the closed-form inertia of its shape, and starts at rest.
"""

from __future__ import annotations

from collections import OrderedDict, defaultdict
from collections.abc import Iterable, Sequence
from itertools import islice
from typing import TYPE_CHECKING, cast

from clutter_gym.datatypes import Obstacle
from clutter_gym.util.transforms import yaw_quat

if TYPE_CHECKING:  # the arena hands the pool its Sim; the pool loads no engine
    from clutter_gym.sim import Sim

PARK_DEPTH = -10.0  # parked bodies wait this far below the floor (metres)
PARK_SPACING = 2.0  # metres between parked bodies: piled at one point, moving each one costs more the more there are
_COLOURS = {"box": (0.62, 0.52, 0.40, 1.0), "cylinder": (0.45, 0.55, 0.45, 1.0), "wall": (0.35, 0.35, 0.38, 1.0),
            "movable box": (0.85, 0.55, 0.25, 1.0), "movable cylinder": (0.80, 0.45, 0.30, 1.0)}


def _key(o: Obstacle) -> tuple:
    return (f"movable {o.shape}" if o.movable else o.shape, o.size)


def inertia(o: Obstacle) -> tuple[float, float, float]:
    """Principal moments of inertia (kg m^2) of a movable obstacle as a solid of uniform density, about its centre."""
    sx, sy, sz = o.size
    if o.shape == "cylinder":
        r = 0.5 * sx
        side = o.mass * (3 * r * r + sz * sz) / 12.0
        return (side, side, 0.5 * o.mass * r * r)
    return (o.mass * (sy * sy + sz * sz) / 12.0, o.mass * (sx * sx + sz * sz) / 12.0,
            o.mass * (sx * sx + sy * sy) / 12.0)


class ObstaclePool:
    """Static bodies for obstacles (reused across resets) and for fixed structure (walls, a table; built once).

    Args:
        sim: the physics client.
        fixed: obstacles present in every scene, drawn in the wall colour.
        max_parked: parked bodies kept for reuse; older ones are deleted.
    """

    def __init__(self, sim: Sim, fixed: tuple[Obstacle, ...] = (), max_parked: int = 48) -> None:
        self._sim = sim
        self.max_parked = max_parked
        self._parked: OrderedDict[int, tuple] = OrderedDict()  # body -> key, least recently parked first
        self._free: dict[tuple, list[int]] = defaultdict(list)
        self._active: dict[int, tuple[tuple, int]] = {}  # obstacle index -> (key, body) of the bodies placed
        self.fixed = fixed
        self.fixed_bodies = []
        for o in fixed:
            (body,) = self._sim.obstacles.add_static_boxes([0.5 * s for s in o.size], _COLOURS["wall"], [o.centre])
            self._sim.obstacles.move_static(body, o.centre, yaw_quat(o.yaw))
            self._sim.obstacles.sleep(body)
            self.fixed_bodies.append(body)

    @property
    def sim(self) -> Sim:
        """The physics client the bodies are in."""
        return self._sim

    @property
    def placed(self) -> dict[int, int]:
        """Obstacle index -> body of every obstacle of the scene that has a body."""
        return {i: body for i, (_, body) in self._active.items()}

    @property
    def size(self) -> int:
        """Obstacle bodies in the world (active and parked)."""
        return len(self._active) + len(self._parked)

    def _create(self, key: tuple, obstacles: list[Obstacle]) -> list[int]:
        """New bodies of shape ``key``, one centred at each of ``obstacles``: static ones in batches, movable ones
        one at a time (they are few, and made at the origin)."""
        shape, size = key
        colour = _COLOURS[shape]
        o = obstacles[0]
        if shape == "movable box":
            return [self._sim.obstacles.add_movable_box([0.5 * s for s in size], colour) for _ in obstacles]
        if shape == "movable cylinder":
            return [self._sim.obstacles.add_movable_cylinder(o.radius, size[2], colour) for _ in obstacles]
        centres = [o.centre for o in obstacles]
        if shape == "box":
            return self._sim.obstacles.add_static_boxes([0.5 * s for s in size], colour, centres)
        return self._sim.obstacles.add_static_cylinders(o.radius, size[2], colour, centres)

    def place(self, obstacles: tuple[Obstacle, ...], shown: Sequence[int] | None = None) -> list[int]:
        """Show exactly ``obstacles`` (in order), or only those with the indices ``shown``, and park the bodies they no
        longer need; returns body ids, -1 for an obstacle not shown.

        The last scene's bodies are reused first (each shape's free list is last in, first out), and those are
        still visible. The obstacles no parked body fits get new bodies, made a shape at a time and then given
        broad-phase entries in scene order, so that contacts are solved as if each had been made in turn. Bodies
        beyond ``max_parked`` are deleted before they would be parked, so a large scene followed by a small one
        costs one removal each."""
        released = list(self._active.values())
        self._release(released)
        indices = range(len(obstacles)) if shown is None else shown
        bodies, made = self._acquire(obstacles, indices, {body for _, body in released})
        self._sim.obstacles.order_broadphase(made)
        self._active = {i: (_key(obstacles[i]), body) for i, body in zip(indices, bodies)}
        self._park(released)
        out = [-1] * len(obstacles)
        for i, body in zip(indices, bodies):
            out[i] = body
        return out

    def update(self, obstacles: tuple[Obstacle, ...], enter: Sequence[int], leave: Sequence[int]) -> None:
        """Give the obstacles with the indices ``enter`` bodies and park those of ``leave``, leaving every other body
        as it is (its cached contacts kept; :attr:`placed` says which bodies there are). The entering bodies get
        broad-phase entries after every other body's, in scene order."""
        released = [self._active.pop(i) for i in leave]
        self._release(released)
        bodies, _ = self._acquire(obstacles, enter, {body for _, body in released})
        self._sim.obstacles.order_broadphase(bodies)
        for i, body in zip(enter, bodies):
            self._active[i] = (_key(obstacles[i]), body)
        self._park(released)

    def _release(self, released: list[tuple[tuple, int]]) -> None:
        """Make ``released`` (key, body) pairs free for reuse; those not reused are parked by :meth:`_park`."""
        for key, body in released:
            self._free[key].append(body)
            self._parked[body] = key

    def _acquire(self, obstacles: tuple[Obstacle, ...], indices: Iterable[int], shown: set[int]
                 ) -> tuple[list[int], list[int]]:
        """Bodies for the obstacles with ``indices``, in place (free ones reused, the missing shapes made in
        batches), and those of them just made, in scene order. ``shown`` are the free bodies still visible."""
        indices = list(indices)
        bodies: list[int | None] = []
        missing: dict[tuple, list[int]] = defaultdict(list)  # shape -> positions in ``indices`` it has no body for
        for n, i in enumerate(indices):
            key = _key(obstacles[i])
            if self._free[key]:
                body = self._free[key].pop()
                del self._parked[body]
                if body not in shown:
                    self._sim.obstacles.set_visible(body, True, _COLOURS[key[0]])
                bodies.append(body)
            else:
                missing[key].append(n)
                bodies.append(None)
        for key, positions in missing.items():
            for n, body in zip(positions, self._create(key, [obstacles[indices[n]] for n in positions])):
                bodies[n] = body
        placed = cast(list[int], bodies)
        for i, body in zip(indices, placed):
            o = obstacles[i]
            self._sim.obstacles.move_static(body, o.centre, yaw_quat(o.yaw))
            if o.movable:  # awake, so that it settles where it was put and stays put by its own contacts
                self._sim.obstacles.set_mass(body, o.mass, inertia(o))
            else:
                self._sim.obstacles.sleep(body)
        return placed, [placed[n] for n in sorted(n for positions in missing.values() for n in positions)]

    def _park(self, released: list[tuple[tuple, int]]) -> None:
        """Park the ``released`` bodies that were not reused, after deleting the oldest beyond ``max_parked``."""
        self._evict()
        for _, body in released:
            if body in self._parked:
                if self._parked[body][0].startswith("movable"):
                    self._sim.obstacles.set_mass(body, 0.0)
                position = (PARK_SPACING * (body % 64), PARK_SPACING * (body // 64), PARK_DEPTH)
                self._sim.obstacles.move_static(body, position, (0.0, 0.0, 0.0, 1.0))
                self._sim.obstacles.sleep(body)
                self._sim.obstacles.set_visible(body, False, _COLOURS[self._parked[body][0]])

    def _evict(self) -> None:
        """Delete the least recently parked bodies beyond ``max_parked``."""
        excess = len(self._parked) - self.max_parked
        if excess <= 0:
            return
        gone = list(islice(self._parked, excess))
        for body in gone:
            self._sim.obstacles.remove_body(body)
            del self._parked[body]
        gone_set = set(gone)
        for key, free in self._free.items():
            self._free[key] = [b for b in free if b not in gone_set]
