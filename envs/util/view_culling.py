"""View culling: which bodies no pixel of a camera frame can show, from bounding spheres (numpy only).

A renderer that transforms every triangle of every shown body, in view or not (TinyRenderer), draws the same image
faster when the bodies it cannot show are hidden for the frame. :class:`ViewCuller` keeps a bounding sphere and the
shown colour of each body it is given and names the bodies whose sphere lies wholly outside a camera's view.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np

#: Added to a body's bounding-sphere radius, in metres: covers the 1 mm margin TinyRenderer's hull of a cylinder
#: visual carries, and rounding.
CULL_MARGIN = 0.01


@functools.lru_cache(maxsize=8)
def _frustum_planes(projection: tuple[float, ...], width: int, height: int) -> np.ndarray:
    """The planes, in eye coordinates, that bound what a camera can draw (Gribb and Hartmann's planes).

    Args:
        projection: OpenGL projection matrix, column-major (16 values).
        width: image width in pixels.
        height: image height in pixels.

    Returns:
        (6, 4) planes, each a unit normal pointing into the view and an offset (metres): the left, right, bottom
        and top of the image widened by a pixel (x and y in normalised device coordinates up to +-(1 + 2 / size)
        still land on a pixel), the plane of the eye and the far plane.
    """
    clip = np.array(projection, dtype=float).reshape(4, 4).T
    sx, sy = 1.0 + 2.0 / width, 1.0 + 2.0 / height
    r0, r1, r2, r3 = clip
    planes = np.array([sx * r3 + r0, sx * r3 - r0, sy * r3 + r1, sy * r3 - r1, r3, r3 - r2])
    return planes / np.linalg.norm(planes[:, :3], axis=1, keepdims=True)


class ViewCuller:
    """Bounding spheres and shown colours of bodies, and which of them a camera frame cannot show.

    A body is added with the radius of a sphere about its origin that holds its visual, and its colour. Bodies whose
    colour is fully transparent (or None) count as hidden: they are never named by :meth:`outside_view`.
    :meth:`move`, :meth:`set_colour` and :meth:`remove` ignore a body that is not tracked (never added, or removed).
    """

    def __init__(self) -> None:
        self._spheres: dict[int, list[float]] = {}  # body -> [x, y, z, radius + CULL_MARGIN], metres
        self._shown: dict[int, tuple[float, ...]] = {}  # body -> rgba, for bodies shown now
        self._table: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # shown bodies, rebuilt on change

    def add(self, body: int, radius: float, rgba: Sequence[float]) -> None:
        """Track a body centred at the origin.

        Args:
            body: the body id.
            radius: radius in metres of a sphere about the body's origin that holds its visual;
                :data:`CULL_MARGIN` is added to it.
            rgba: the body's colour, each channel in [0, 1] (alpha 0: hidden).
        """
        self._spheres[body] = [0.0, 0.0, 0.0, float(radius) + CULL_MARGIN]
        self._set_shown(body, tuple(rgba))

    def move(self, body: int, centre: Sequence[float] | np.ndarray) -> None:
        """Put a tracked body's sphere at ``centre`` (world frame, metres)."""
        sphere = self._spheres.get(body)
        if sphere is not None:
            sphere[:3] = centre
            self._table = None

    def set_colour(self, body: int, rgba: Sequence[float] | None) -> None:
        """Record a tracked body's colour (alpha 0 or None: hidden, never named by :meth:`outside_view`)."""
        if body in self._spheres:
            self._set_shown(body, None if rgba is None else tuple(rgba))

    def remove(self, body: int) -> None:
        """Stop tracking a body."""
        self._spheres.pop(body, None)
        self._set_shown(body, None)

    def colour(self, body: int) -> tuple[float, ...]:
        """The colour a shown body gets back after a frame it was hidden for.

        Raises:
            KeyError: the body is not tracked or is hidden.
        """
        return self._shown[body]

    def outside_view(self, view: Sequence[float], projection: Sequence[float], width: int, height: int) -> list[int]:
        """The shown bodies that no pixel of this camera can show.

        A body is named when its sphere lies wholly behind the eye, beyond the far plane, or more than a pixel past a
        side of the image: every triangle of it then lands outside the viewport, behind the eye or past the far
        plane, so hiding it changes no pixel.

        Args:
            view: OpenGL view matrix, column-major (16 values, metres), as for pybullet's ``getCameraImage``.
            projection: OpenGL projection matrix, column-major (16 values).
            width: image width in pixels.
            height: image height in pixels.

        Returns:
            The ids of those bodies.
        """
        if self._table is None:
            bodies = list(self._shown)
            spheres = np.array([self._spheres[b] for b in bodies], dtype=float).reshape(-1, 4)
            centres = np.vstack([spheres[:, :3].T, np.ones(len(bodies))])
            self._table = (np.array(bodies, dtype=int), centres, -spheres[:, 3])
        bodies, centres, neg_radii = self._table
        planes = _frustum_planes(tuple(projection), width, height) @ np.array(view, dtype=float).reshape(4, 4).T
        return bodies[(planes @ centres < neg_radii).any(axis=0)].tolist()

    def _set_shown(self, body: int, rgba: tuple[float, ...] | None) -> None:
        if rgba is None or rgba[3] == 0.0:
            self._shown.pop(body, None)
        else:
            self._shown[body] = rgba
        self._table = None
