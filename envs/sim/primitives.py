""":class:`PrimitiveTable`: the boxes and cylinders a Sim made, where they are now and whether they are shown.

What the ray-cast camera (:mod:`clutter_gym.sim.ray_casting`) draws: every obstacle body, the drawn ground and the
markers, as exact shapes. Robots loaded from URDF files are not in it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clutter_gym.sim.ray_casting import BOX, CYLINDER

_KINDS = {"box": BOX, "cylinder": CYLINDER}


class PrimitiveTable:
    """One row per tracked body: its shape (a box or an upright cylinder in the body frame, centred at an offset from
    the body origin), its pose and whether it is shown. :meth:`move`, :meth:`show` and :meth:`remove` ignore a body
    that is not tracked."""

    def __init__(self) -> None:
        self._rows: dict[int, tuple[int, np.ndarray, np.ndarray]] = {}  # body -> (kind, halves, offset)
        self._poses: dict[int, tuple] = {}  # body -> (position, rotation) as given; converted in arrays()
        self._hidden: set[int] = set()
        self._arrays: tuple[np.ndarray, ...] | None = None  # shown rows, rebuilt on change

    def add(self, body: int, kind: str, halves: Sequence[float], position: Sequence[float],
            offset: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Track a body, unrotated at ``position``.

        Args:
            body: the body id.
            kind: "box" or "cylinder" (upright along the body's z axis).
            halves: a box's half extents, or a cylinder's (radius, radius, half height), metres.
            position: the body origin, world frame, metres.
            offset: the shape's centre in the body frame, metres.
        """
        self._rows[body] = (_KINDS[kind], np.array(halves, dtype=float), np.array(offset, dtype=float))
        self.move(body, position, np.eye(3))

    def move(self, body: int, position: Sequence[float], rotation: np.ndarray | Sequence[float]) -> None:
        """Put a tracked body at ``position`` (metres) turned by ``rotation`` (3, 3, or its 9 values row by row),
        world frame."""
        if body in self._rows:
            self._poses[body] = (tuple(position), rotation)
            self._arrays = None

    def show(self, body: int, shown: bool) -> None:
        """Draw a tracked body or not."""
        if body in self._rows:
            (self._hidden.discard if shown else self._hidden.add)(body)
            self._arrays = None

    def remove(self, body: int) -> None:
        """Stop tracking a body."""
        self._rows.pop(body, None)
        self._poses.pop(body, None)
        self._hidden.discard(body)
        self._arrays = None

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The shown bodies as :func:`~clutter_gym.sim.ray_casting.cast_depth` takes them: (bodies (n,), kinds (n,),
        centres (n, 3), rotations (n, 3, 3), halves (n, 3))."""
        if self._arrays is None:
            bodies = [b for b in self._rows if b not in self._hidden]
            rows = [self._rows[b] for b in bodies]
            poses = [self._poses[b] for b in bodies]
            positions = np.array([p for p, _ in poses], dtype=float).reshape(-1, 3)
            rotations = np.array([np.ravel(r) for _, r in poses], dtype=float).reshape(-1, 3, 3)
            offsets = np.array([offset for _, _, offset in rows], dtype=float).reshape(-1, 3)
            centres = positions + np.einsum("nij,nj->ni", rotations, offsets)
            self._arrays = (
                np.array(bodies, dtype=np.int64),
                np.array([kind for kind, _, _ in rows], dtype=np.int64),
                centres,
                rotations,
                np.array([halves for _, halves, _ in rows], dtype=float).reshape(-1, 3),
            )
        return self._arrays
