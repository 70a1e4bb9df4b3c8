"""RGB and depth camera noise: pure functions of (clean image, rng, params, episode state, intrinsics).

Every stage is skipped when its parameters are zero, and clean parameters return the input array itself (not a
copy) without touching the generator. Magnitudes and sources: ``sensor-noise-reference.md`` sections 3 and 6.

RGB (uint8 in, uint8 out), in order: lens distortion (bilinear, edge pixels replicated beyond the rendered field)
-> per-episode global and per-channel gains -> shot noise -> read noise -> round and clip to [0, 255].

Depth (metres in, float32 metres out, 0.0 = no data as on Azure Kinect / RealSense), in order: lens distortion
(nearest neighbour, so no interpolated "flying pixels"; rays beyond the rendered field read 0) -> lateral jitter
-> per-episode bias -> axial noise -> quantisation -> range limits -> edge holes -> random holes. Input pixels that
are not finite and positive are treated as no data.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from scipy.special import ndtri

from clutter_gym.noise.distortion import Distortion, Intrinsics, distortion_resampler
from clutter_gym.noise.params import NoiseParams, param

SHOT_EXACT_BELOW = 30.0
"""Shot noise is drawn exactly (Poisson) for pixels expecting fewer electrons than this; above, as a Gaussian of
the same mean and variance (folded into the read-noise draw). At 30 e- the Poisson skewness is 0.18 and the
difference is far below one 8-bit step."""


@dataclasses.dataclass(frozen=True)
class LensNoise(NoiseParams):
    """Brown-Conrady lens distortion coefficients, shared by the colour and depth images (0 = a pinhole)."""

    k1: float = param(0.0, -1.0, 1.0, "", "radial distortion r^2 coefficient (< 0 barrel)")
    k2: float = param(0.0, -1.0, 1.0, "", "radial distortion r^4 coefficient")
    k3: float = param(0.0, -1.0, 1.0, "", "radial distortion r^6 coefficient")
    p1: float = param(0.0, -1.0, 1.0, "", "tangential distortion coefficient p1")
    p2: float = param(0.0, -1.0, 1.0, "", "tangential distortion coefficient p2")

    @property
    def distortion(self) -> Distortion:
        return Distortion(self.k1, self.k2, self.p1, self.p2, self.k3)


@dataclasses.dataclass(frozen=True)
class RgbNoise(LensNoise):
    """Colour camera noise. Defaults are a clean camera. Values are 1-sigma unless stated."""

    section = "camera_rgb"

    read_sigma: float = param(0.0, 0.0, 50.0, "DN", "Gaussian read noise in 8-bit digital numbers")
    shot_electrons: float = param(
        0.0, 0.0, 1e6, "e-", "electrons collected at full scale (255 DN): s in [0, 1] -> Poisson(s N) / N; 0 = none"
    )
    gain_sigma: float = param(0.0, 0.0, 0.5, "", "per-episode global gain error, fraction (gain = 1 + sigma n)")
    color_sigma: float = param(0.0, 0.0, 0.5, "", "per-episode per-channel gain error, fraction")


@dataclasses.dataclass(frozen=True)
class DepthNoise(LensNoise):
    """Depth camera noise, sigma_z = sigma_c0 + sigma_c2 (z - sigma_z0)^2. Defaults are a clean camera."""

    section = "camera_depth"

    sigma_c0: float = param(0.0, 0.0, 0.1, "m", "axial noise: constant term")
    sigma_c2: float = param(0.0, 0.0, 0.1, "1/m", "axial noise: quadratic term")
    sigma_z0: float = param(0.0, 0.0, 5.0, "m", "axial noise: depth of the minimum")
    bias_m: float = param(0.0, 0.0, 0.5, "m", "per-episode bias u (bias_m + bias_frac z), u ~ U[-1, 1]: constant")
    bias_frac: float = param(0.0, 0.0, 0.1, "", "per-episode bias: fraction of depth")
    quantization_c2: float = param(
        0.0, 0.0, 0.1, "1/m", "disparity quantisation: inverse depth rounded to steps of this (depth step c2 z^2)"
    )
    quantization_m: float = param(0.0, 0.0, 0.1, "m", "output quantisation: depth rounded to multiples of this")
    lateral_sigma_px: float = param(0.0, 0.0, 3.0, "px", "per-pixel jitter of where depth is sampled")
    hole_prob: float = param(0.0, 0.0, 1.0, "", "probability that a pixel reads no data")
    edge_hole_prob: float = param(0.0, 0.0, 1.0, "", "probability that a pixel at a depth discontinuity reads no data")
    edge_threshold_m: float = param(0.05, 0.001, 10.0, "m", "|dz| to a 4-neighbour that makes a discontinuity")
    min_depth: float = param(0.0, 0.0, 10.0, "m", "readings nearer than this read no data")
    max_depth: float = param(1000.0, 0.1, 1000.0, "m", "readings farther than this read no data")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.min_depth >= self.max_depth:
            raise ValueError(
                f"{self.section}.min_depth ({self.min_depth} m) must be below max_depth ({self.max_depth} m)"
            )


@dataclasses.dataclass(frozen=True)
class RgbEpisode:
    """Per-episode RGB state: the gain of each channel (global gain times colour gain, never negative)."""

    gains: tuple[float, float, float] = (1.0, 1.0, 1.0)


@dataclasses.dataclass(frozen=True)
class DepthEpisode:
    """Per-episode depth state: ``bias_u`` in [-1, 1]; the bias at depth z is bias_u (bias_m + bias_frac z)."""

    bias_u: float = 0.0


def start_rgb_episode(rng: np.random.Generator, params: RgbNoise) -> RgbEpisode:
    """Draw the episode's gains: global 1 + gain_sigma n, times per-channel 1 + color_sigma n_c (none when 0)."""
    gains = np.ones(3)
    if params.gain_sigma > 0:
        gains *= 1.0 + params.gain_sigma * rng.standard_normal()
    if params.color_sigma > 0:
        gains *= 1.0 + params.color_sigma * rng.standard_normal(3)
    g = np.maximum(gains, 0.0)
    return RgbEpisode((float(g[0]), float(g[1]), float(g[2])))


def start_depth_episode(rng: np.random.Generator, params: DepthNoise) -> DepthEpisode:
    """Draw the episode's bias factor u ~ U[-1, 1] (nothing drawn without a bias)."""
    if params.bias_m > 0 or params.bias_frac > 0:
        return DepthEpisode(float(rng.uniform(-1.0, 1.0)))
    return DepthEpisode()


@functools.lru_cache(maxsize=1)
def _normal_table() -> np.ndarray:
    table = ndtri((np.arange(65536) + 0.5) / 65536.0)
    table /= table.std()
    table = table.astype(np.float32)
    table.setflags(write=False)
    return table


def standard_normal(rng: np.random.Generator, shape: tuple[int, ...] | int) -> np.ndarray:
    """Standard normal float32 draws, cheaper than ``rng.standard_normal`` for per-pixel noise.

    A uniform 16-bit integer indexes the 65536 quantile midpoints of N(0, 1) (rescaled to unit variance): the
    distribution is exact to 2^-16 in probability, with the tails cut at 4.3 sigma (probability 1.7e-5).
    """
    return _normal_table()[rng.integers(0, 65536, size=shape, dtype=np.uint16)]


def _check_shape(image: np.ndarray, intrinsics: Intrinsics, channels: tuple[int, ...]) -> None:
    expected = (intrinsics.height, intrinsics.width, *channels)
    if image.shape != expected:
        raise ValueError(f"image shape {image.shape} does not match the camera intrinsics {expected}")


def apply_rgb_noise(
    rgb: np.ndarray, rng: np.random.Generator, params: RgbNoise, episode: RgbEpisode, intrinsics: Intrinsics
) -> np.ndarray:
    """A noisy copy of an (H, W, 3) uint8 image (the input itself, untouched, when ``params`` are clean)."""
    if params.is_clean:
        return rgb
    _check_shape(rgb, intrinsics, (3,))
    if rgb.dtype != np.uint8:
        raise ValueError(f"apply_rgb_noise takes a uint8 image, got {rgb.dtype}")
    lens = params.distortion
    if not lens.is_identity:
        x = distortion_resampler(intrinsics, lens, 1, False)(rgb)  # float32, edge pixels replicated
    else:
        x = rgb.astype(np.float32)
    if episode.gains != (1.0, 1.0, 1.0):
        x *= np.asarray(episode.gains, dtype=np.float32)
    read_var = np.float32(params.read_sigma**2)
    sigma: np.ndarray | np.float32 | None = np.float32(params.read_sigma) if params.read_sigma > 0 else None
    if params.shot_electrons > 0:
        dn_per_e = np.float32(255.0 / params.shot_electrons)
        var = x * dn_per_e  # variance of Poisson(lam) / N * 255 in DN^2, lam = x / dn_per_e
        var += read_var
        low = x < SHOT_EXACT_BELOW * dn_per_e
        n_low = int(np.count_nonzero(low))
        if n_low:  # few expected electrons: exact Poisson counts, only read noise left for the Gaussian
            x[low] = rng.poisson(x[low] / dn_per_e) * dn_per_e
            var[low] = read_var
        if params.read_sigma > 0 or n_low < low.size:
            sigma = np.sqrt(var, out=var)
    if sigma is not None:
        noise = standard_normal(rng, x.shape)
        noise *= sigma
        x += noise
    np.clip(x, 0.0, 255.0, out=x)
    np.rint(x, out=x)
    return x.astype(np.uint8)


@functools.lru_cache(maxsize=8)
def _jitter_table(sigma: float) -> np.ndarray:
    """round(sigma n), n ~ N(0, 1), at the 65536 quantile midpoints: indexed by a uniform uint16 it samples the
    rounded Gaussian exactly to 2^-16 in probability (offsets beyond about 4.3 sigma never occur)."""
    table = np.rint(sigma * ndtri((np.arange(65536) + 0.5) / 65536.0)).astype(np.intp)
    table.setflags(write=False)
    return table


@functools.lru_cache(maxsize=8)
def _pixel_grid(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = np.divmod(np.arange(height * width), width)
    rows.setflags(write=False)
    cols.setflags(write=False)
    return rows, cols


def _edge_pixels(z: np.ndarray, threshold: float) -> np.ndarray:
    """Pixels with a 4-neighbour more than ``threshold`` away in depth (both sides of every jump)."""
    edge = np.zeros(z.shape, dtype=bool)
    jump = np.abs(np.diff(z, axis=1)) > threshold
    edge[:, :-1] |= jump
    edge[:, 1:] |= jump
    jump = np.abs(np.diff(z, axis=0)) > threshold
    edge[:-1] |= jump
    edge[1:] |= jump
    return edge


def apply_depth_noise(
    depth: np.ndarray, rng: np.random.Generator, params: DepthNoise, episode: DepthEpisode, intrinsics: Intrinsics
) -> np.ndarray:
    """A noisy float32 copy of an (H, W) depth image in metres, 0.0 = no data (the input itself when clean)."""
    if params.is_clean:
        return depth
    _check_shape(depth, intrinsics, ())
    h, w = depth.shape
    src = np.asarray(depth, dtype=np.float64).ravel()
    src = np.where((src > 0) & (src < np.inf), src, 0.0)  # NaN, inf and <= 0 are no data
    # Where every output pixel samples the clean image: lens distortion (nearest, off-field rays read no data),
    # then lateral jitter in the distorted image; composed into one gather.
    lens = params.distortion
    index = None
    if not lens.is_identity:
        sampler = distortion_resampler(intrinsics, lens, 0, True)
        index = sampler.index
        if sampler.uses_fill:
            src = np.append(src, 0.0)
    if params.lateral_sigma_px > 0:
        table = _jitter_table(params.lateral_sigma_px)
        rows, cols = _pixel_grid(h, w)
        draws = rng.integers(0, 65536, size=(2, h * w), dtype=np.uint16)
        jrow = np.clip(rows + table[draws[0]], 0, h - 1)
        jcol = np.clip(cols + table[draws[1]], 0, w - 1)
        flat = jrow * w + jcol
        index = flat if index is None else index[flat]
    z_geo = src if index is None else src[index]  # (h * w,) the geometry the sensor looks at
    valid = z_geo > 0
    z = z_geo
    if episode.bias_u != 0.0:
        z = z + episode.bias_u * (params.bias_m + params.bias_frac * z_geo)
    if params.sigma_c0 > 0 or params.sigma_c2 > 0:
        sigma = params.sigma_c0 + params.sigma_c2 * (z_geo - params.sigma_z0) ** 2
        z = z + sigma * standard_normal(rng, h * w)
    if params.quantization_c2 > 0:
        # Stereo disparity is quantised: the inverse depth is rounded to steps of c2, so the depth levels are
        # 1 / (n c2) with spacing ~ c2 z^2. Fewer than half a step of disparity (n = 0) is no data.
        c2 = params.quantization_c2
        n = np.rint(1.0 / (c2 * np.maximum(z, 1e-9)))
        z = np.where(n >= 1, 1.0 / (c2 * np.maximum(n, 1.0)), 0.0)
    if params.quantization_m > 0:
        m = params.quantization_m
        z = np.rint(z / m) * m
    ok = valid & (z >= params.min_depth) & (z <= params.max_depth) & (z > 0)
    if params.edge_hole_prob > 0:
        edge = _edge_pixels(z_geo.reshape(h, w), params.edge_threshold_m).ravel()
        where = np.flatnonzero(edge)
        ok[where[rng.random(where.size) < params.edge_hole_prob]] = False
    if params.hole_prob > 0:
        ok &= rng.random(h * w, dtype=np.float32) >= np.float32(params.hole_prob)
    return np.where(ok, z, 0.0).astype(np.float32).reshape(h, w)
