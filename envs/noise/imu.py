"""IMU noise: white noise, bias drift, turn-on bias, scale factor, misalignment, saturation and quantisation.

Pure functions on plain arrays, no simulator. A reading is the 6-vector of :class:`clutter_gym.sensors.imu.Imu`:
specific force ``(f_x, f_y, f_z)`` in m/s^2 then angular rate ``(w_x, w_y, w_z)`` in rad/s, IMU frame.

Model, for sample ``k`` of a sequence spaced ``dt`` seconds apart, separately for the accelerometer and the gyro::

    y_k = Q(sat(M @ x_k + b0 + d_k + sigma_w * n_k))        n_k ~ N(0, I)
    sigma_w = ND / sqrt(dt)                                  (white noise of the mean over one sample period)
    d_k = d_{k-1} + K * sqrt(dt) * e_k                       (tau == 0: bias random walk)
    d_k = a * d_{k-1} + K * sqrt(tau / 2) * sqrt(1 - a^2) * e_k,   a = exp(-dt / tau)   (tau > 0: Gauss-Markov)

with ``x`` the clean reading, ``M = diag(1 + s) + (off-diagonal misalignment)`` and ``b0`` (turn-on bias) drawn
once per episode, ``d`` the in-run bias drift, carried between calls in :class:`ImuEpisode`, ``sat`` clipping
at full scale and ``Q`` rounding to the nearest multiple of the LSB. The Gauss-Markov drift has stationary
standard deviation ``K * sqrt(tau / 2)``, so over times much shorter than ``tau`` it grows like the random walk
``K`` (the model of PX4's Gazebo IMU plugin, which also keeps the turn-on bias constant and separate). In Allan
deviation terms, white noise gives ``ND / sqrt(tau)`` and the random walk ``K * sqrt(tau / 3)``.

Typical magnitudes (``docs/sensor-noise-reference.md`` section 4, nominal ADIS16448-class): gyro ND
1.7e-4 rad/s/sqrt(Hz), accel ND 2e-3 m/s^2/sqrt(Hz), gyro K 2.2e-5 rad/s^2/sqrt(Hz), accel K 8.6e-4
m/s^3/sqrt(Hz), turn-on 0.0087 rad/s and 0.196 m/s^2, tau 1000 s (gyro) and 300 s (accel).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from scipy.signal import lfilter

from clutter_gym.noise.params import NoiseParams, param

__all__ = ["ACCEL_RANGE", "GYRO_RANGE", "ImuEpisode", "ImuNoise", "apply_imu_noise", "start_imu_episode", "white_sigma"]

#: Full scale of the accelerometer, m/s^2 (16 g, a common MEMS setting), and of the gyro, rad/s (2000 deg/s): the
#: clean sensor's (:class:`clutter_gym.sensors.imu.ImuConfig`) and the noise model's default.
ACCEL_RANGE = 16 * 9.80665
GYRO_RANGE = float(np.deg2rad(2000.0))


@dataclass(frozen=True)
class ImuNoise(NoiseParams):
    """IMU noise parameters. The defaults mean "no noise" (only the full-scale clipping of a real IMU remains).

    Attributes:
        gyro_noise_density: gyro white noise (angle random walk), rad/s/sqrt(Hz).
        accel_noise_density: accelerometer white noise (velocity random walk), m/s^2/sqrt(Hz).
        gyro_random_walk: gyro bias random walk K, rad/s^2/sqrt(Hz).
        accel_random_walk: accelerometer bias random walk K, m/s^3/sqrt(Hz).
        gyro_bias_tau: correlation time of the gyro bias, s; 0 = infinite (pure random walk), otherwise a
            first-order Gauss-Markov bias with stationary std ``gyro_random_walk * sqrt(tau / 2)``.
        accel_bias_tau: the same for the accelerometer bias, s.
        gyro_turn_on_sigma: std of the per-episode constant gyro bias (bias repeatability), rad/s.
        accel_turn_on_sigma: std of the per-episode constant accelerometer bias, m/s^2.
        scale_sigma: std of the per-episode, per-axis scale-factor error (fraction; 0.01 = 1 %), both sensors.
        misalignment_sigma: std of the per-episode off-diagonal cross-axis coupling terms (small angles), rad.
        accel_quantization: accelerometer LSB, m/s^2; 0 = not quantised.
        gyro_quantization: gyro LSB, rad/s; 0 = not quantised.
        accel_range: accelerometer full scale, m/s^2 (16 g). Readings always saturate here, noisy or clean.
        gyro_range: gyro full scale, rad/s (2000 deg/s). Readings always saturate here, noisy or clean.
    """

    section: ClassVar[str] = "imu"

    gyro_noise_density: float = param(0.0, 0.0, 0.1, "rad/s/sqrt(Hz)", "gyro white noise density")
    accel_noise_density: float = param(0.0, 0.0, 1.0, "m/s^2/sqrt(Hz)", "accelerometer white noise density")
    gyro_random_walk: float = param(0.0, 0.0, 0.1, "rad/s^2/sqrt(Hz)", "gyro bias random walk")
    accel_random_walk: float = param(0.0, 0.0, 1.0, "m/s^3/sqrt(Hz)", "accelerometer bias random walk")
    gyro_bias_tau: float = param(0.0, 0.0, 1e6, "s", "gyro bias correlation time; 0 = pure random walk")
    accel_bias_tau: float = param(0.0, 0.0, 1e6, "s", "accelerometer bias correlation time; 0 = pure random walk")
    gyro_turn_on_sigma: float = param(0.0, 0.0, 1.0, "rad/s", "std of the per-episode gyro bias")
    accel_turn_on_sigma: float = param(0.0, 0.0, 2.0, "m/s^2", "std of the per-episode accelerometer bias")
    scale_sigma: float = param(0.0, 0.0, 0.2, "", "std of the per-episode per-axis scale-factor error (fraction)")
    misalignment_sigma: float = param(0.0, 0.0, 0.1, "rad", "std of the per-episode cross-axis coupling terms")
    accel_quantization: float = param(0.0, 0.0, 1.0, "m/s^2", "accelerometer LSB; 0 = none")
    gyro_quantization: float = param(0.0, 0.0, 0.1, "rad/s", "gyro LSB; 0 = none")
    accel_range: float = param(ACCEL_RANGE, 1.0, 1000.0, "m/s^2", "accelerometer full scale (clipping)")
    gyro_range: float = param(GYRO_RANGE, 0.1, 100.0, "rad/s", "gyro full scale (clipping)")


@dataclass
class ImuEpisode:
    """Per-episode IMU error state, made by :func:`start_imu_episode`.

    Attributes:
        turn_on_bias: (6,) constant bias drawn at the start of the episode, accel m/s^2 then gyro rad/s.
        bias: (6,) in-run bias drift ``d`` of the last generated sample (starts at 0), same units. The only
            thing :func:`apply_imu_noise` mutates, in place.
        matrix: (6, 6) block-diagonal sensitivity matrix ``M``: accel block ``[:3, :3]``, gyro block ``[3:, 3:]``,
            each ``diag(1 + scale error)`` plus off-diagonal misalignment. Identity when both are off.
    """

    turn_on_bias: np.ndarray = field(default_factory=lambda: np.zeros(6))
    bias: np.ndarray = field(default_factory=lambda: np.zeros(6))
    matrix: np.ndarray = field(default_factory=lambda: np.eye(6))


def white_sigma(density: float, dt: float) -> float:
    """Per-sample std of white noise averaged over one sample period: ``density / sqrt(dt)``.

    Args:
        density: noise density, units/sqrt(Hz).
        dt: sample period, s (> 0).

    Returns:
        The std of one sample, in the density's units.
    """
    return density / math.sqrt(dt)


_DIAGONAL = np.arange(6) * 7  # flat indices into a (6, 6) matrix
_OFF_DIAGONAL = np.array([6 * r + c for r in range(6) for c in range(6) if r != c and r // 3 == c // 3])


def start_imu_episode(rng: np.random.Generator, params: ImuNoise) -> ImuEpisode:
    """Draw the per-episode errors: turn-on bias, scale factors and misalignment. Bias drift starts at 0.

    ``turn_on_bias ~ N(0, turn_on_sigma)`` per axis; ``M = diag(1 + N(0, scale_sigma))`` per axis, plus
    ``N(0, misalignment_sigma)`` on each of the 6 off-diagonal terms, for the accelerometer and the gyro. Nothing
    is drawn for a parameter that is 0, so a clean profile consumes no randomness; the draws that are needed
    come from a single ``rng.standard_normal`` call.

    Args:
        rng: the episode's random generator.
        params: the IMU noise parameters.

    Returns:
        A fresh :class:`ImuEpisode`.
    """
    p = params
    sizes = (
        3 if p.accel_turn_on_sigma > 0 else 0,
        3 if p.gyro_turn_on_sigma > 0 else 0,
        6 if p.scale_sigma > 0 else 0,
        12 if p.misalignment_sigma > 0 else 0,
    )
    episode = ImuEpisode()
    total = sum(sizes)
    if total == 0:
        return episode
    z = rng.standard_normal(total)
    i = 0
    if sizes[0]:
        episode.turn_on_bias[:3] = p.accel_turn_on_sigma * z[i : i + 3]
        i += 3
    if sizes[1]:
        episode.turn_on_bias[3:] = p.gyro_turn_on_sigma * z[i : i + 3]
        i += 3
    if sizes[2]:
        episode.matrix.flat[_DIAGONAL] += p.scale_sigma * z[i : i + 6]
        i += 6
    if sizes[3]:  # row-major: accel (0,1) (0,2) (1,0) (1,2) (2,0) (2,1), then the same for the gyro block
        episode.matrix.flat[_OFF_DIAGONAL] = p.misalignment_sigma * z[i : i + 12]
    return episode


class _Plan:
    """Per-(params, dt) constants for :func:`apply_imu_noise`, so the per-step path does no setup work.

    The normals of one call are drawn as one (n, n_white + n_bias) block; the white columns map to
    ``white_cols`` of the reading and the bias columns to ``bias_cols``. Both are contiguous slices because the
    active sensors are either accel (0:3), gyro (3:6) or both (0:6).
    """

    __slots__ = (
        "bound", "matrix", "offset", "n_white", "white_cols", "white_sigma", "n_draw", "bias_cols", "bias_a",
        "bias_c", "bias_groups", "quant_cols", "lsb",
    )  # fmt: skip

    def __init__(self, p: ImuNoise, dt: float) -> None:
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"imu noise: dt must be a positive number of seconds, got {dt!r}")

        def cols(accel: bool, gyro: bool) -> slice | None:
            return slice(0 if accel else 3, 6 if gyro else 3) if (accel or gyro) else None

        def per_axis(which: slice, accel: float, gyro: float) -> np.ndarray:
            return np.array([accel] * 3 + [gyro] * 3)[which]

        self.matrix = p.scale_sigma > 0 or p.misalignment_sigma > 0
        self.white_cols = cols(p.accel_noise_density > 0, p.gyro_noise_density > 0)
        self.n_white = 0
        if self.white_cols is not None:
            accel, gyro = white_sigma(p.accel_noise_density, dt), white_sigma(p.gyro_noise_density, dt)
            self.white_sigma = per_axis(self.white_cols, accel, gyro)
            self.n_white = len(self.white_sigma)

        # Bias drift: one group per active sensor, (reading cols, draw cols, a, c, tau): d <- a d + c e.
        self.bias_cols = cols(p.accel_random_walk > 0, p.gyro_random_walk > 0)
        self.bias_groups: list[tuple[slice, slice, float, float, float]] = []
        a_c = [(1.0, 0.0)] * 2
        for i, (k, tau) in enumerate(((p.accel_random_walk, p.accel_bias_tau), (p.gyro_random_walk, p.gyro_bias_tau))):
            if k == 0:
                continue
            if tau == 0:
                a, c = 1.0, k * math.sqrt(dt)
            else:
                a = math.exp(-dt / tau)
                c = k * math.sqrt(tau / 2.0) * math.sqrt(-math.expm1(-2.0 * dt / tau))  # sigma_ss * sqrt(1 - a^2)
            a_c[i] = (a, c)
            start = self.n_white + 3 * len(self.bias_groups)
            self.bias_groups.append((slice(3 * i, 3 * i + 3), slice(start, start + 3), a, c, tau))
        self.n_draw = self.n_white + 3 * len(self.bias_groups)
        if self.bias_cols is not None:
            self.bias_a = per_axis(self.bias_cols, a_c[0][0], a_c[1][0])
            self.bias_c = per_axis(self.bias_cols, a_c[0][1], a_c[1][1])
        self.offset = self.bias_cols is not None or p.accel_turn_on_sigma > 0 or p.gyro_turn_on_sigma > 0

        # Saturation, then quantisation. With an LSB the largest level is the last multiple of it within range,
        # so a saturated, quantised reading never exceeds full scale.
        lsb = (p.accel_quantization, p.gyro_quantization)
        full = (p.accel_range, p.gyro_range)
        top = [r if q == 0 else q * math.floor(r / q * (1 + 1e-12)) for r, q in zip(full, lsb)]
        self.bound = np.array([top[0]] * 3 + [top[1]] * 3)
        self.quant_cols = cols(lsb[0] > 0, lsb[1] > 0)
        if self.quant_cols is not None:
            self.lsb = per_axis(self.quant_cols, *lsb)


@functools.lru_cache(maxsize=64)
def _plan(params: ImuNoise, dt: float) -> _Plan:
    return _Plan(params, dt)


def apply_imu_noise(
    clean: np.ndarray, rng: np.random.Generator, params: ImuNoise, episode: ImuEpisode, dt: float
) -> np.ndarray:
    """Corrupt clean IMU readings: ``y = Q(sat(M @ x + b0 + d_k + ND / sqrt(dt) * n_k))`` (see module docstring).

    For each sample the bias drift first advances one step of ``dt`` (random walk ``d += K * sqrt(dt) * e`` when
    tau is 0, else Gauss-Markov ``d = a * d + K * sqrt(tau / 2) * sqrt(1 - a^2) * e`` with ``a = exp(-dt / tau)``),
    then the reading gets the scale/misalignment matrix, turn-on bias, drift and white noise of std
    ``ND / sqrt(dt)``, is clipped at full scale and rounded to the nearest multiple of the LSB. Terms whose
    parameter is 0 are skipped; all normals of a call come from one ``rng.standard_normal`` call, none when the
    parameters are clean, in which case the result equals ``clip(clean, -range, range)`` bit for bit.

    Args:
        clean: (6,) one reading or (n, 6) n readings spaced ``dt`` apart: specific force m/s^2 then angular
            rate rad/s, IMU frame.
        rng: random generator.
        params: noise parameters.
        episode: state from :func:`start_imu_episode` with the same ``params``. Its ``bias`` is updated in place
            to the drift of the last sample (the only mutation), so consecutive calls continue the drift.
        dt: spacing of the samples, s (the env's control period; the native sample period for a raw stream).

    Returns:
        A new float64 array shaped like ``clean``.

    Raises:
        ValueError: if ``clean`` is not (6,) or (n, 6), or ``dt`` is not positive.
    """
    plan = _plan(params, dt)
    x = np.asarray(clean, dtype=np.float64)
    if x.shape[-1:] != (6,) or x.ndim > 2:
        raise ValueError(f"imu noise: clean readings must be shaped (6,) or (n, 6), got {x.shape}")

    y = x @ episode.matrix.T if plan.matrix else x.copy()
    drift = episode.bias
    if plan.n_draw and x.ndim == 1:  # one sample: the per-step path, kept to a handful of small numpy calls
        z = rng.standard_normal(plan.n_draw)
        if plan.n_white:
            y[plan.white_cols] += plan.white_sigma * z[: plan.n_white]
        if plan.bias_groups:
            cols = plan.bias_cols
            drift[cols] = plan.bias_a * drift[cols] + plan.bias_c * z[plan.n_white :]
    elif plan.n_draw and len(x):  # n samples: work in place on the draws (they are large for long sequences)
        z = rng.standard_normal((len(x), plan.n_draw))
        if plan.n_white:
            white = z[:, : plan.n_white]
            white *= plan.white_sigma
            y[:, plan.white_cols] += white
        for cols, draws, a, c, tau in plan.bias_groups:
            steps = z[:, draws]
            steps *= c
            if tau == 0:
                path = np.cumsum(steps, axis=0, out=steps)
                path += drift[cols]
            else:
                path = lfilter([1.0], [1.0, -a], steps, axis=0, zi=a * drift[None, cols])[0]
            y[:, cols] += path
            drift[cols] = path[-1]
    if plan.offset:
        y += episode.turn_on_bias + drift if x.ndim == 1 and plan.bias_groups else episode.turn_on_bias
    np.minimum(np.maximum(y, -plan.bound, out=y), plan.bound, out=y)
    if plan.quant_cols is not None:
        q = y[..., plan.quant_cols]  # a view: round in place
        q /= plan.lsb
        np.round(q, out=q)
        q *= plan.lsb
    return y
