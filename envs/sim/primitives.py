""":class:`PrimitiveTable`: the boxes and cylinders a Sim made, where they are now and whether they are shown.

What the ray-cast camera (:mod:`clutter_gym.sim.ray_casting`) draws: every obstacle body, the drawn ground and the
markers, as exact shapes; and what the exact LIDAR caster hits: the solid ones (obstacles, shown or parked), the
ground being its plane. Robots loaded from URDF files are not in it.

A large scene keeps its far static obstacles out of the physics world (``worlds/near_field.py``); the sensors still
see them as the table's *backdrop*: rows with no body, shown while their obstacle has none, reported with the id
:data:`BACKDROP_ID`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import cast

import numpy as np

from clutter_gym.sim.ray_casting import BOX, CYLINDER

_KINDS = {"box": BOX, "cylinder": CYLINDER}
#: The id :meth:`PrimitiveTable.arrays` gives backdrop rows: an obstacle that has no body now.
BACKDROP_ID = -2
#: bodies (n,), kinds (n,), centres (n, 3), rotations (n, 3, 3), halves (n, 3): what the casters take
Arrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class PrimitiveTable:
    """One row per tracked body: its shape (a box or an upright cylinder in the body frame, centred at an offset from
    the body origin), its pose, whether it is shown and whether rays hit it. :meth:`move`, :meth:`show` and
    :meth:`remove` ignore a body that is not tracked."""

    def __init__(self) -> None:
        self._rows: dict[int, tuple[int, np.ndarray, np.ndarray, bool]] = {}  # body -> (kind, halves, offset, solid)
        self._poses: dict[int, tuple] = {}  # body -> (position, rotation) as given; converted in the arrays
        self._hidden: set[int] = set()
        # rows as arrays, rebuilt after a body is added or removed; the rows of moved bodies are updated when asked for
        self._shown: tuple[tuple[np.ndarray, ...], dict[int, int]] | None = None
        self._solid: tuple[tuple[np.ndarray, ...], dict[int, int]] | None = None
        self._moved: set[int] = set()
        # the backdrop: (kinds, centres, rotations, halves) of shapes without a body, and which of them are shown
        self._backdrop: tuple[np.ndarray, ...] | None = None
        self._backdrop_shown = np.zeros(0, dtype=bool)
        self._any_shown = False  # self._backdrop_shown.any(), asked at every cast
        self._joined: dict[str, tuple[np.ndarray, ...]] = {}  # "shown"/"solid" tables with the shown backdrop rows

    def __contains__(self, body: int) -> bool:
        return body in self._rows

    def add(self, body: int, kind: str, halves: Sequence[float], position: Sequence[float],
            offset: Sequence[float] = (0.0, 0.0, 0.0), solid: bool = True) -> None:
        """Track a body, unrotated at ``position``.

        Args:
            body: the body id.
            kind: "box" or "cylinder" (upright along the body's z axis).
            halves: a box's half extents, or a cylinder's (radius, radius, half height), metres.
            position: the body origin, world frame, metres.
            offset: the shape's centre in the body frame, metres.
            solid: whether rays hit it (not a marker, which has no collision shape, nor the ground's drawn square).
        """
        self._rows[body] = (_KINDS[kind], np.array(halves, dtype=float), np.array(offset, dtype=float), solid)
        self._poses[body] = (tuple(position), np.eye(3))
        self._shown = self._solid = None
        self._joined.clear()

    def set_backdrop(self, kinds: Sequence[str], centres: np.ndarray, rotations: np.ndarray, halves: np.ndarray
                     ) -> None:
        """Replace the backdrop with these solid shapes, none of them shown yet (:meth:`show_backdrop`).

        Args:
            kinds: "box" or "cylinder" per shape.
            centres, rotations, halves: (n, 3), (n, 3, 3) and (n, 3), as :meth:`add` and :meth:`move` take them.
        """
        self._backdrop = (np.array([_KINDS[k] for k in kinds], dtype=np.int64).reshape(-1),
                          np.array(centres, dtype=float).reshape(-1, 3),
                          np.array(rotations, dtype=float).reshape(-1, 3, 3),
                          np.array(halves, dtype=float).reshape(-1, 3))
        self._backdrop_shown = np.zeros(len(self._backdrop[0]), dtype=bool)
        self._any_shown = False
        self._joined.clear()

    def show_backdrop(self, shown: np.ndarray) -> None:
        """Which backdrop rows rays and the camera see: a boolean per row of :meth:`set_backdrop`."""
        if self._backdrop is None or len(shown) != len(self._backdrop_shown):
            raise ValueError(f"need one flag per backdrop row ({len(self._backdrop_shown)}), got {len(shown)}")
        self._backdrop_shown = np.array(shown, dtype=bool)
        self._any_shown = bool(self._backdrop_shown.any())
        self._joined.clear()

    @property
    def backdrop_shown(self) -> bool:
        """Whether some backdrop row is shown: something rays can hit has no pybullet body."""
        return self._any_shown

    def clear_backdrop(self) -> None:
        """No backdrop."""
        self._backdrop, self._backdrop_shown, self._any_shown = None, np.zeros(0, dtype=bool), False
        self._joined.clear()

    def move(self, body: int, position: Sequence[float] | np.ndarray, rotation: np.ndarray | Sequence[float]) -> None:
        """Put a tracked body at ``position`` (metres) turned by ``rotation`` (3, 3, or its 9 values row by row),
        world frame."""
        if body in self._rows:
            self._poses[body] = (tuple(position), rotation)
            self._moved.add(body)

    def show(self, body: int, shown: bool) -> None:
        """Draw a tracked body or not."""
        if body in self._rows and (body in self._hidden) == shown:
            (self._hidden.discard if shown else self._hidden.add)(body)
            self._shown = None
            self._joined.pop("shown", None)

    def remove(self, body: int) -> None:
        """Stop tracking a body."""
        self._rows.pop(body, None)
        self._poses.pop(body, None)
        self._hidden.discard(body)
        self._moved.discard(body)
        self._shown = self._solid = None
        self._joined.clear()

    def arrays(self) -> Arrays:
        """The shown bodies as :func:`~clutter_gym.sim.ray_casting.cast_depth` takes them: (bodies (n,), kinds (n,),
        centres (n, 3), rotations (n, 3, 3), halves (n, 3)), then the shown backdrop rows (id :data:`BACKDROP_ID`)."""
        self._follow_moves()
        if self._shown is None:
            self._shown = self._table([b for b in self._rows if b not in self._hidden])
        return self._with_backdrop("shown", self._shown[0])

    def solids(self) -> Arrays:
        """The bodies rays hit, shown or not, and the shown backdrop rows, as :meth:`arrays` gives them."""
        self._follow_moves()
        if self._solid is None:
            self._solid = self._table([b for b, row in self._rows.items() if row[3]])
        return self._with_backdrop("solid", self._solid[0])

    def _with_backdrop(self, name: str, table: tuple[np.ndarray, ...]) -> Arrays:
        """``table`` followed by the shown backdrop rows; joined once per change of either (the bodies' rows are
        copied in again only after one of them moved)."""
        if self._backdrop is None or not self._any_shown:
            return cast(Arrays, table)
        if name not in self._joined:
            kinds, centres, rotations, halves = (a[self._backdrop_shown] for a in self._backdrop)
            ids = np.full(len(kinds), BACKDROP_ID, dtype=np.int64)
            self._joined[name] = tuple(np.concatenate((a, b)) for a, b in zip(table, (ids, kinds, centres, rotations,
                                                                                      halves)))
        joined = self._joined[name]
        n = len(table[0])
        for a, b in zip(joined[2:4], table[2:4]):  # bodies' centres and rotations: they may have moved since
            a[:n] = b
        return cast(Arrays, joined)

    def _follow_moves(self) -> None:
        """Write the poses of the bodies moved since the last call into the built tables' rows."""
        if not self._moved:
            return
        for table in (self._shown, self._solid):
            if table is None:
                continue
            (_, _, centres, rotations, _), index = table
            bodies = [b for b in self._moved if b in index]
            if bodies:
                rows = [index[b] for b in bodies]
                positions, turned, offsets = self._poses_of(bodies)
                rotations[rows] = turned
                centres[rows] = positions + np.einsum("nij,nj->ni", turned, offsets)
        self._moved.clear()

    def _poses_of(self, bodies: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(n, 3) positions, (n, 3, 3) rotations and (n, 3) shape offsets of ``bodies``."""
        poses = [self._poses[b] for b in bodies]
        positions = np.array([p for p, _ in poses], dtype=float).reshape(-1, 3)
        rotations = np.array([np.ravel(r) for _, r in poses], dtype=float).reshape(-1, 3, 3)
        offsets = np.array([self._rows[b][2] for b in bodies], dtype=float).reshape(-1, 3)
        return positions, rotations, offsets

    def _table(self, bodies: list[int]) -> tuple[tuple[np.ndarray, ...], dict[int, int]]:
        rows = [self._rows[b] for b in bodies]
        positions, rotations, offsets = self._poses_of(bodies)
        centres = positions + np.einsum("nij,nj->ni", rotations, offsets)
        arrays = (
            np.array(bodies, dtype=np.int64),
            np.array([row[0] for row in rows], dtype=np.int64),
            centres,
            rotations,
            np.array([row[1] for row in rows], dtype=float).reshape(-1, 3),
        )
        return arrays, {b: i for i, b in enumerate(bodies)}
