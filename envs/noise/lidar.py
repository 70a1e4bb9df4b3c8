"""2D/3D LIDAR range noise: a pure function of (clean ranges, rng, params, episode).

Model, applied to every beam that returned (clean range below the maximum), in this order:

* per-episode bias ``b(r) = u * max(bias_m, bias_frac * r)`` with one ``u ~ U(-1, 1)`` per episode (per unit);
* Gaussian range noise with ``sigma(r) = max(range_sigma, range_sigma_frac * r)`` (constant near, proportional
  far: the "+-10 mm or 1 %" form of LIDAR datasheets);
* spurious short returns: with probability ``spurious_prob`` the beam reads ``U(min_range, r)`` (dust, glass,
  mixed pixels);
* dropouts: with probability ``dropout_prob`` the beam returns nothing;
* quantisation to ``quantization`` metres (round to nearest);
* clipping: a reading outside the sensor's window ``[min_range, max_range]`` is a no-return.

A no-return reads ``max_range`` (``no_return="max"``, the clean sensor's convention and the observation's) or
``inf`` (``no_return="inf"``, the ROS ``LaserScan`` convention). Angular jitter moves the beams themselves, so it is
applied by the sensor before the rays are cast (:func:`angle_offsets`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clutter_gym.noise.params import NoiseParams, choice, param


@dataclass(frozen=True)
class LidarNoise(NoiseParams):
    """LIDAR noise parameters (all zero = the clean scan)."""

    section = "lidar"
    range_sigma: float = param(0.0, 0.0, 1.0, "m", "constant part of the range noise 1-sigma")
    range_sigma_frac: float = param(0.0, 0.0, 0.5, "", "range noise 1-sigma as a fraction of range")
    bias_m: float = param(0.0, 0.0, 1.0, "m", "per-episode bias bound, constant part")
    bias_frac: float = param(0.0, 0.0, 0.5, "", "per-episode bias bound as a fraction of range")
    dropout_prob: float = param(0.0, 0.0, 1.0, "", "probability that a beam returns nothing")
    spurious_prob: float = param(0.0, 0.0, 1.0, "", "probability of a spurious short return")
    quantization: float = param(0.0, 0.0, 1.0, "m", "range resolution (0 = continuous)")
    angular_jitter: float = param(0.0, 0.0, 0.1, "rad", "1-sigma error of each beam's angle")
    max_range: float = param(1000.0, 0.01, 1000.0, "m", "sensor's maximum range (the env's lidar_range also caps)")
    min_range: float = param(0.0, 0.0, 10.0, "m", "sensor's minimum range (the env's minimum also applies)")
    no_return: str = choice("max", ("max", "inf"), "what a beam without a return reads")


@dataclass
class LidarEpisode:
    """Per-episode draws: the unit's bias factor ``u`` in [-1, 1]."""

    bias_u: float = 0.0


def start_lidar_episode(rng: np.random.Generator, params: LidarNoise) -> LidarEpisode:
    """Draw the per-episode bias factor (nothing is drawn when the bias is zero)."""
    if params.bias_m == 0.0 and params.bias_frac == 0.0:
        return LidarEpisode()
    return LidarEpisode(bias_u=float(rng.uniform(-1.0, 1.0)))


def angle_offsets(shape: tuple[int, ...], rng: np.random.Generator, params: LidarNoise) -> np.ndarray | None:
    """Gaussian errors of the beams' azimuths (radians), or None when there is no jitter (cast the fixed beams)."""
    if params.angular_jitter == 0.0:
        return None
    return rng.normal(0.0, params.angular_jitter, shape)


def apply_lidar_noise(
    ranges: np.ndarray,
    rng: np.random.Generator,
    params: LidarNoise,
    episode: LidarEpisode,
    min_range: float,
    max_range: float,
) -> np.ndarray:
    """Noisy ranges in metres from clean ones (any shape; ``max_range`` or more in the input = no return).

    Args:
        ranges: clean ranges, metres.
        rng: the episode's noise generator.
        params: noise parameters.
        episode: per-episode draws from :func:`start_lidar_episode`.
        min_range, max_range: the scan geometry's window, metres; the sensor's own window (``params``) narrows it.
    """
    if params.is_clean:
        return ranges
    lo = max(min_range, params.min_range)
    hi = min(max_range, params.max_range)
    r = np.array(ranges, dtype=np.float64)
    hit = r < max_range
    if episode.bias_u != 0.0:
        r += episode.bias_u * np.maximum(params.bias_m, params.bias_frac * r)
    if params.range_sigma > 0.0 or params.range_sigma_frac > 0.0:
        r += np.maximum(params.range_sigma, params.range_sigma_frac * r) * rng.standard_normal(r.shape)
    if params.spurious_prob > 0.0 or params.dropout_prob > 0.0:
        u = rng.random((2, *r.shape))  # one draw for both: row 0 spurious, row 1 dropout
        spurious = u[0] < params.spurious_prob
        if spurious.any():
            # given u < p, u / p is uniform on [0, 1): it places the spurious return, no second draw needed
            r[spurious] = lo + u[0][spurious] / params.spurious_prob * np.maximum(r[spurious] - lo, 0.0)
        if params.dropout_prob > 0.0:
            hit &= u[1] >= params.dropout_prob
    if params.quantization > 0.0:
        r /= params.quantization
        np.rint(r, out=r)
        r *= params.quantization
    hit &= r >= lo
    hit &= r <= hi
    r[~hit] = math.inf if params.no_return == "inf" else max_range
    return r
