"""Brown–Conrady (radial-tangential) lens distortion and the image resampling that applies it.

Conventions
-----------
* Pixel coordinates: ``u`` is the column, ``v`` the row. The centre of pixel ``[row i, column j]`` lies at
  ``(u, v) = (j, i)``, so an image of width ``W`` spans ``u`` in ``[-0.5, W - 0.5]`` and its middle is at
  ``(W - 1) / 2``. Normalised coordinates are ``x = (u - cx) / fx``, ``y = (v - cy) / fy``.
* Distortion coefficients are given in OpenCV order ``(k1, k2, p1, p2, k3)``; :class:`Distortion` builds them by
  name. The model maps an ideal (pinhole) normalised point to where the lens puts it::

      r2 = x² + y²,  radial = 1 + k1 r2 + k2 r2² + k3 r2³
      xd = x radial + 2 p1 x y + p2 (r2 + 2 x²)
      yd = y radial + p1 (r2 + 2 y²) + 2 p2 x y

  ``k1 < 0`` is barrel distortion (points move toward the centre), ``k1 > 0`` pincushion.
* A remap sends every pixel of the DISTORTED output image to the (float) position in the ideal pinhole image that
  it shows; resampling gathers the ideal image there. Positions whose ray the lens cannot produce (the inverse
  does not converge, only possible for strong distortion) are NaN in the maps and read as "outside".
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import scipy.sparse

UNDISTORT_TOL = 1e-12
"""Fixed-point iteration of :func:`undistort_normalized` stops once no coordinate moved more than this."""

UNDISTORT_MAX_ITER = 200
"""At most this many fixed-point iterations; points still unconverged (or off by > 1e-9) come back NaN."""


class Distortion(NamedTuple):
    """Brown–Conrady coefficients in OpenCV order (hashable, so usable as a cache key)."""

    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    k3: float = 0.0

    @property
    def is_identity(self) -> bool:
        return not any(self)


@dataclasses.dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics of an image of ``width`` x ``height`` pixels (focal lengths and centre in pixels)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_fov(cls, width: int, height: int, vertical_fov_rad: float) -> Intrinsics:
        """Square pixels whose vertical field of view spans the outer edges of the top and bottom pixel rows.

        ``fy = (height / 2) / tan(vfov / 2)``, ``fx = fy``, and the optical axis through the image middle,
        ``cx = (width - 1) / 2``, ``cy = (height - 1) / 2`` (pixel centres at integer coordinates; this matches an
        OpenGL / pybullet projection with that vertical FOV).
        """
        if not 0.0 < vertical_fov_rad < math.pi:
            raise ValueError(f"vertical_fov_rad must be in (0, pi), got {vertical_fov_rad!r}")
        fy = (height / 2.0) / math.tan(vertical_fov_rad / 2.0)
        return cls(int(width), int(height), fy, fy, (width - 1) / 2.0, (height - 1) / 2.0)


def _coeffs(k: Sequence[float]) -> Distortion:
    if len(k) != 5:
        raise ValueError(f"distortion coefficients must be (k1, k2, p1, p2, k3), got {k!r}")
    return Distortion(*(float(c) for c in k))


def distort_normalized(x: np.ndarray, y: np.ndarray, k: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Ideal normalised coordinates -> distorted ones (element-wise; ``k`` in OpenCV order)."""
    k1, k2, p1, p2, k3 = _coeffs(k)
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xy2 = 2.0 * x * y
    xd = x * radial + p1 * xy2 + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + p2 * xy2
    return xd, yd


def undistort_normalized(
    xd: np.ndarray, yd: np.ndarray, k: Sequence[float], iterations: int = UNDISTORT_MAX_ITER
) -> tuple[np.ndarray, np.ndarray]:
    """Distorted normalised coordinates -> ideal ones, by the fixed-point iteration OpenCV's undistortPoints uses.

    ``x <- (xd - tangential(x)) / radial(x)`` starting from ``x = xd``, until no coordinate moves more than
    :data:`UNDISTORT_TOL` or after ``iterations`` rounds. Points whose result does not reproduce ``(xd, yd)`` to
    1e-9 under :func:`distort_normalized` (no inverse: beyond the fold of a strong distortion) are NaN.
    """
    coeffs = _coeffs(k)
    k1, k2, p1, p2, k3 = coeffs
    xd = np.asarray(xd, dtype=np.float64)
    yd = np.asarray(yd, dtype=np.float64)
    if coeffs.is_identity:
        return xd.copy(), yd.copy()
    x, y = xd.copy(), yd.copy()
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for _ in range(iterations):
            r2 = x * x + y * y
            radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
            xy2 = 2.0 * x * y
            x_new = (xd - p1 * xy2 - p2 * (r2 + 2.0 * x * x)) / radial
            y_new = (yd - p1 * (r2 + 2.0 * y * y) - p2 * xy2) / radial
            step = max(float(np.max(np.abs(x_new - x), initial=0.0)), float(np.max(np.abs(y_new - y), initial=0.0)))
            x, y = x_new, y_new
            if step <= UNDISTORT_TOL:  # NaN steps never pass, so divergence runs out the iterations
                break
        rx, ry = distort_normalized(x, y, coeffs)
        bad = ~((np.abs(rx - xd) <= 1e-9) & (np.abs(ry - yd) <= 1e-9))
    if np.any(bad):
        x = np.where(bad, np.nan, x)
        y = np.where(bad, np.nan, y)
    return x, y


def distortion_remap(
    width: int, height: int, fx: float, fy: float, cx: float, cy: float, k: Sequence[float]
) -> tuple[np.ndarray, np.ndarray]:
    """(map_rows, map_cols), each (height, width) float64 and read-only: for every pixel of the distorted output
    image, the row / column position in the ideal pinhole image it samples (NaN where no ray maps there).

    Cached per camera (the arrays are shared, hence read-only).
    """
    return _distortion_remap(int(width), int(height), float(fx), float(fy), float(cx), float(cy), _coeffs(k))


@functools.lru_cache(maxsize=32)
def _distortion_remap(
    width: int, height: int, fx: float, fy: float, cx: float, cy: float, k: Distortion
) -> tuple[np.ndarray, np.ndarray]:
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    if k.is_identity:  # exactly the pixel grid (the round trip through normalised coordinates is not bit-exact)
        rows, cols = v, u
    else:
        x, y = undistort_normalized((u - cx) / fx, (v - cy) / fy, k)
        rows, cols = y * fy + cy, x * fx + cx
    rows.setflags(write=False)
    cols.setflags(write=False)
    return rows, cols


@dataclasses.dataclass(frozen=True, eq=False)
class Resampler:
    """A precomputed gather that resamples a (H, W) or (H, W, C) source onto an output grid.

    Nearest neighbour keeps ``index`` (N,), the flat source index of every output pixel; bilinear keeps
    ``matrix``, a sparse (N, H * W [+ 1]) float32 matrix with the (up to) four weights of every output pixel.
    Index ``H * W`` (the extra column) is the fill value, present only when ``uses_fill``.
    """

    source_shape: tuple[int, int]
    output_shape: tuple[int, int]
    index: np.ndarray | None
    matrix: scipy.sparse.csr_array | None
    uses_fill: bool

    @property
    def order(self) -> int:
        return 0 if self.matrix is None else 1

    def __call__(self, image: np.ndarray, fill: float = 0.0) -> np.ndarray:
        """Resample ``image``: nearest keeps the dtype; bilinear returns floats, unrounded (float64 for float64
        images, float32 otherwise)."""
        h, w = self.source_shape
        if image.shape[:2] != (h, w):
            raise ValueError(f"image shape {image.shape} does not match the resampler's source {self.source_shape}")
        channels = image.shape[2:]
        src = image.reshape(h * w, -1)
        if self.uses_fill:
            src = np.concatenate([src, np.full((1, src.shape[1]), fill, dtype=src.dtype)])
        if self.matrix is None:
            assert self.index is not None  # nearest neighbour keeps the index
            out = np.take(src, self.index, axis=0)
        else:
            out = self.matrix @ (src if src.dtype in (np.float32, np.float64) else src.astype(np.float32))
        return out.reshape(self.output_shape + channels)


def make_resampler(
    maps: tuple[np.ndarray, np.ndarray], source_shape: tuple[int, int], order: int = 1, fill: bool = False
) -> Resampler:
    """Gather tables for ``maps = (rows, cols)`` over a source of ``source_shape = (H, W)``.

    ``order`` 0 is nearest neighbour (the depth path: no interpolated "flying pixels" across object edges), 1
    bilinear. Positions within the image footprint (half a pixel around the outer pixel centres) interpolate with
    edge clamping. Positions outside it clamp to the edge when ``fill`` is False ("nearest" mode) and read the fill
    value when ``fill`` is True. NaN positions (no ray) always read the fill value.
    """
    if order not in (0, 1):
        raise ValueError(f"order must be 0 (nearest) or 1 (bilinear), got {order!r}")
    rows, cols = (np.asarray(m, dtype=np.float64) for m in maps)
    if rows.shape != cols.shape or rows.ndim != 2:
        raise ValueError(f"maps must be two arrays of the same 2-D shape, got {rows.shape} and {cols.shape}")
    h, w = (int(s) for s in source_shape)
    n = rows.size
    sentinel = h * w
    finite = np.isfinite(rows) & np.isfinite(cols)
    inside = finite & (rows >= -0.5) & (rows < h - 0.5) & (cols >= -0.5) & (cols < w - 0.5)
    outside = (~inside if fill else ~finite).ravel()
    uses_fill = bool(np.any(outside))
    r = np.clip(np.where(finite, rows, 0.0), 0.0, h - 1.0).ravel()
    c = np.clip(np.where(finite, cols, 0.0), 0.0, w - 1.0).ravel()
    if order == 0:
        index = np.rint(r).astype(np.intp) * w + np.rint(c).astype(np.intp)
        index[outside] = sentinel
        index.setflags(write=False)
        return Resampler((h, w), rows.shape, index, None, uses_fill)
    r0 = np.minimum(np.floor(r), max(h - 2, 0)).astype(np.intp)
    c0 = np.minimum(np.floor(c), max(w - 2, 0)).astype(np.intp)
    fr, fc = r - r0, c - c0
    r1, c1 = np.minimum(r0 + 1, h - 1), np.minimum(c0 + 1, w - 1)
    index = np.stack([r0 * w + c0, r0 * w + c1, r1 * w + c0, r1 * w + c1], axis=1)  # (n, 4)
    weight = np.stack([(1 - fr) * (1 - fc), (1 - fr) * fc, fr * (1 - fc), fr * fc], axis=1)
    index[outside] = sentinel
    weight[outside] = (1.0, 0.0, 0.0, 0.0)
    matrix = scipy.sparse.csr_array(
        (weight.astype(np.float32).ravel(), index.ravel(), np.arange(0, 4 * n + 1, 4)),
        shape=(n, h * w + int(uses_fill)),
    )
    return Resampler((h, w), rows.shape, None, matrix, uses_fill)


@functools.lru_cache(maxsize=32)
def distortion_resampler(intrinsics: Intrinsics, k: Distortion, order: int, fill: bool) -> Resampler:
    """The cached :class:`Resampler` that applies lens distortion ``k`` to images of camera ``intrinsics``."""
    i = intrinsics
    maps = _distortion_remap(i.width, i.height, i.fx, i.fy, i.cx, i.cy, _coeffs(k))
    return make_resampler(maps, (i.height, i.width), order, fill)


def remap(
    image: np.ndarray, maps: tuple[np.ndarray, np.ndarray], order: int = 1, fill: float | None = None
) -> np.ndarray:
    """Resample an (H, W) or (H, W, C) image at ``maps = (rows, cols)`` (from :func:`distortion_remap`).

    ``order`` 0 = nearest (use it for depth), 1 = bilinear. ``fill`` None = "nearest" edge mode (positions off the
    image clamp to the edge); a number = positions off the image (beyond half a pixel past the outer pixel
    centres) read ``fill``. NaN positions (no ray) read ``fill``, or 0 in edge mode. The output has the input's
    dtype (bilinear results of integer images are rounded and clipped to the dtype's range).
    """
    image = np.asarray(image)
    if image.ndim not in (2, 3):
        raise ValueError(f"image must be (H, W) or (H, W, C), got shape {image.shape}")
    sampler = make_resampler(maps, image.shape[:2], order, fill is not None)
    out = sampler(image, 0.0 if fill is None else fill)
    if out.dtype == image.dtype:
        return out
    if np.issubdtype(image.dtype, np.integer):
        info = np.iinfo(image.dtype)
        out = np.clip(np.rint(out), info.min, info.max)
    return out.astype(image.dtype)
