"""Statistical tests of the IMU noise model (clutter_gym.noise.imu): every parameter is recovered from the output.

Fixed seeds throughout. Each tolerance is stated next to the estimator's own spread (measured over 20 seeds when
the tests were written), so a failure means the model is wrong, not that the seed was unlucky.
"""

from __future__ import annotations

import allantools
import numpy as np
import pytest

from clutter_gym.noise.imu import ImuNoise, apply_imu_noise, start_imu_episode, white_sigma
from clutter_gym.sensors.imu import ImuConfig

RATE = 200.0
DT = 1.0 / RATE
STATIC = np.array([0.0, 0.0, 9.81, 0.0, 0.0, 0.0])  # at rest, z up: +g specific force, no rotation

# Nominal profile of docs/sensor-noise-reference.md (ADIS16448 / BMI160 class).
NOMINAL = ImuNoise(
    gyro_noise_density=1.7e-4,
    accel_noise_density=2.0e-3,
    gyro_random_walk=2.2e-5,
    accel_random_walk=8.6e-4,
    gyro_bias_tau=1000.0,
    accel_bias_tau=300.0,
    gyro_turn_on_sigma=0.0087,
    accel_turn_on_sigma=0.196,
    scale_sigma=0.005,
    misalignment_sigma=1e-3,
)
LSB = (16 * 9.80665 / 2**15, np.deg2rad(2000.0) / 2**15)  # 16-bit converters at 16 g and 2000 deg/s


def static(n: int) -> np.ndarray:
    return np.tile(STATIC, (n, 1))


def run(params: ImuNoise, clean: np.ndarray, seed: int, dt: float = DT) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return apply_imu_noise(clean, rng, params, start_imu_episode(rng, params), dt)


def adev(y: np.ndarray, taus: list[float]) -> np.ndarray:
    """Overlapping Allan deviation of each column of y (sampled at RATE), shape (len(taus), columns)."""
    out = [allantools.oadev(col, rate=RATE, data_type="freq", taus=taus) for col in y.T]
    for taus_out, *_ in out:
        np.testing.assert_allclose(taus_out, taus)  # allantools silently drops taus it cannot compute
    return np.stack([dev for _, dev, *_ in out], axis=1)


# 1. White noise ----------------------------------------------------------------------------------------------


def test_white_noise_std_and_allan_deviation_at_the_sample_period():
    params = ImuNoise(gyro_noise_density=1.7e-4, accel_noise_density=2.0e-3)
    nd = np.array([params.accel_noise_density] * 3 + [params.gyro_noise_density] * 3)
    y = run(params, static(200_000), seed=1)
    noise = y - STATIC

    # Std of a 2e5-sample std estimate is 1/sqrt(2n) = 0.16 %; 5 % is the spec'd tolerance.
    np.testing.assert_allclose(noise.std(axis=0), nd / np.sqrt(DT), rtol=0.05)
    assert white_sigma(params.gyro_noise_density, DT) == pytest.approx(params.gyro_noise_density * np.sqrt(RATE))

    # White frequency noise: ADEV(tau) = ND / sqrt(tau), at tau = dt (m = 1) and tau = 20 dt.
    taus = [DT, 20 * DT]
    np.testing.assert_allclose(adev(y, taus), nd / np.sqrt(np.array(taus))[:, None], rtol=0.10)


# 2. Bias random walk -----------------------------------------------------------------------------------------


def test_random_walk_allan_deviation_and_slope():
    # Same ND and K on all 6 axes, 1e6 samples at 200 Hz (5000 s). ADEV^2 = ND^2 / tau + K^2 tau / 3: at
    # tau >= 10 s the white term is < 0.3 % of the variance, so the long-tau ADEV is the random walk.
    nd, k = 1e-3, 1e-3
    params = ImuNoise(gyro_noise_density=nd, accel_noise_density=nd, gyro_random_walk=k, accel_random_walk=k)
    y = run(params, static(1_000_000), seed=2)
    taus = np.array([DT, 0.1, 10.0, 20.0, 50.0])
    avar = (adev(y, list(taus)) ** 2).mean(axis=1)  # average Allan variance over the 6 axes
    measured = np.sqrt(avar)

    # Short tau: white noise, ADEV = ND / sqrt(tau). Estimator spread over 20 seeds: 0.03 % and 0.14 %.
    np.testing.assert_allclose(measured[:2], nd / np.sqrt(taus[:2]), rtol=0.05)

    # Long tau: random walk, ADEV = K sqrt(tau / 3). With only 5000 s of data the 6-axis average still has a
    # seed-to-seed spread of 1.3 / 1.7 / 2.5 % at 10 / 20 / 50 s (worst of 20 seeds: 3.5 / 5.1 / 5.8 %), so
    # 10 % is > 4 sigma at the longest tau while a wrong K (e.g. K*sqrt(2), or tau/2 in place of tau/3) fails.
    model = np.sqrt(nd**2 / taus + k**2 * taus / 3)
    np.testing.assert_allclose(measured[2:], k * np.sqrt(taus[2:] / 3), rtol=0.10)
    np.testing.assert_allclose(measured, model, rtol=0.10)

    # Log-log slope between 10 s and 50 s is +1/2 for a random walk (0.491 with the small white term). Seed
    # spread: sd 0.012, worst of 20 seeds 0.036 off; white noise alone would give -0.5, a ramp +1.
    slope = np.log(measured[4] / measured[2]) / np.log(taus[4] / taus[2])
    assert slope == pytest.approx(0.5, abs=0.05)


# 3. Gauss-Markov bias ----------------------------------------------------------------------------------------


def test_gauss_markov_bias_std_and_lag_one_correlation():
    # Bias only (no white noise, zero input): the output is the bias itself. 1e6 samples = 5000 s, i.e. 2500
    # correlation times for the accel (tau 2 s) and 5000 for the gyro (tau 1 s).
    params = ImuNoise(accel_random_walk=2e-2, gyro_random_walk=1e-3, accel_bias_tau=2.0, gyro_bias_tau=1.0)
    tau = np.array([params.accel_bias_tau] * 3 + [params.gyro_bias_tau] * 3)
    k = np.array([params.accel_random_walk] * 3 + [params.gyro_random_walk] * 3)
    bias = run(params, np.zeros((1_000_000, 6)), seed=3)
    bias = bias[int(20 * tau.max() / DT) :]  # drop the start-up transient from d = 0 (20 correlation times)

    # Stationary std K sqrt(tau / 2). The std estimate of a GM process over T has relative sd ~ sqrt(tau / 2T)
    # (1 % / 0.7 % per axis here); averaging the variance of the 3 axes of each sensor: sd 0.7 % / 0.5 %
    # over 20 seeds, so 5 % is > 7 sigma.
    sigma_ss = k * np.sqrt(tau / 2)
    var = bias.var(axis=0)
    np.testing.assert_allclose(np.sqrt(var.reshape(2, 3).mean(axis=1)), sigma_ss[::3], rtol=0.05)

    # Lag-1 autocorrelation exp(-dt / tau) = 0.9975 / 0.9950. Compare 1 - rho (the part that depends on tau):
    # per-axis spread 2-3 %, 3-axis mean 1.3 %; 10 % would still catch a tau off by 10 %.
    centred = bias - bias.mean(axis=0)
    rho = (centred[1:] * centred[:-1]).sum(axis=0) / (centred * centred).sum(axis=0)
    decay = (1 - rho).reshape(2, 3).mean(axis=1)
    np.testing.assert_allclose(decay, 1 - np.exp(-DT / tau[::3]), rtol=0.10)


# 4. Per-episode draws ----------------------------------------------------------------------------------------


def test_turn_on_bias_scale_and_misalignment_spread():
    params = ImuNoise(gyro_turn_on_sigma=0.0087, accel_turn_on_sigma=0.196, scale_sigma=0.005, misalignment_sigma=1e-3)
    rng = np.random.default_rng(4)
    episodes = [start_imu_episode(rng, params) for _ in range(20_000)]
    turn_on = np.array([e.turn_on_bias for e in episodes])  # (20000, 6)
    matrix = np.array([e.matrix for e in episodes])  # (20000, 6, 6)

    # 60,000 draws per quantity (120,000 for the off-diagonals): a std estimate has sd 0.3 % (0.2 %), so 5 % is
    # ~17 sigma; the means must be zero within 5 standard errors.
    for draws, sigma in [
        (turn_on[:, :3], params.accel_turn_on_sigma),
        (turn_on[:, 3:], params.gyro_turn_on_sigma),
        (np.stack([np.diagonal(m) for m in matrix]) - 1.0, params.scale_sigma),
        (
            matrix[:, (0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5), (1, 2, 0, 2, 0, 1, 4, 5, 3, 5, 3, 4)],
            params.misalignment_sigma,
        ),
    ]:
        assert draws.std() == pytest.approx(sigma, rel=0.05)
        assert abs(draws.mean()) < 5 * sigma / np.sqrt(draws.size)

    # No coupling between the accelerometer and the gyro, and the drift starts at zero.
    assert not matrix[:, :3, 3:].any() and not matrix[:, 3:, :3].any()
    assert not any(e.bias.any() for e in episodes)
    # The turn-on bias is the constant offset a static, otherwise clean IMU reads.
    only_turn_on = params.replace({"scale_sigma": 0.0, "misalignment_sigma": 0.0})
    episode = start_imu_episode(rng, only_turn_on)
    y = apply_imu_noise(static(10), rng, only_turn_on, episode, DT)
    np.testing.assert_allclose(y - STATIC, np.tile(episode.turn_on_bias, (10, 1)), rtol=0, atol=1e-12)


# 5. Quantisation and saturation ------------------------------------------------------------------------------


def test_quantisation_is_exact_and_within_half_an_lsb():
    params = NOMINAL.replace({"accel_quantization": LSB[0], "gyro_quantization": LSB[1]})
    lsb = np.array([LSB[0]] * 3 + [LSB[1]] * 3)
    rng = np.random.default_rng(5)
    clean = rng.uniform(-1, 1, (100_000, 6)) * [50, 50, 50, 5, 5, 5]
    y = run(params, clean, seed=6)
    unquantised = run(NOMINAL, clean, seed=6)  # quantisation draws nothing: the same noise, before rounding

    np.testing.assert_allclose(y / lsb, np.round(y / lsb), rtol=0, atol=1e-9)
    error = y - unquantised
    assert np.all(np.abs(error) <= lsb / 2 * (1 + 1e-9))
    # The rounding error of a signal spread over many LSBs is uniform: std lsb / sqrt(12) (sd of the estimate
    # 0.2 % with 1e5 samples).
    np.testing.assert_allclose(error.std(axis=0), lsb / np.sqrt(12), rtol=0.05)


def test_saturation_clips_exactly_at_full_scale():
    params = NOMINAL
    beyond = np.array([200.0, -200.0, 9.81, 40.0, -40.0, 0.0])
    y = run(params, np.tile(beyond, (100, 1)), seed=7)
    assert np.all(y[:, 0] == params.accel_range) and np.all(y[:, 1] == -params.accel_range)
    assert np.all(y[:, 3] == params.gyro_range) and np.all(y[:, 4] == -params.gyro_range)
    assert np.all(np.abs(y[:, [2, 5]]) < [params.accel_range, params.gyro_range])

    # With an LSB that does not divide the range, saturation goes to the last level within full scale.
    coarse = params.replace({"accel_range": 10.0, "accel_quantization": 0.3})
    y = run(coarse, np.tile(beyond, (100, 1)), seed=7)
    np.testing.assert_allclose(y[:, :2], np.tile([9.9, -9.9], (100, 1)), rtol=0, atol=1e-12)


# 6. Clean parameters -----------------------------------------------------------------------------------------


def test_clean_params_return_the_clean_reading_and_draw_nothing():
    params = ImuNoise()
    assert params.is_clean
    config = ImuConfig(dt=DT)  # the clean sensor saturates at the same full scale
    assert (params.accel_range, params.gyro_range) == (config.accel_range, config.gyro_range)

    rng = np.random.default_rng(8)
    before = rng.bit_generator.state
    episode = start_imu_episode(rng, params)
    clean = np.random.default_rng(9).normal(0, 5, (1000, 6))
    clean[0] = [200.0, -200.0, 9.81, 40.0, -40.0, 0.0]  # beyond full scale: clipped exactly as the clean sensor
    bound = np.array([config.accel_range] * 3 + [config.gyro_range] * 3)
    expected = np.minimum(np.maximum(clean, -bound), bound)

    assert np.array_equal(apply_imu_noise(clean, rng, params, episode, DT), expected)
    assert np.array_equal(apply_imu_noise(clean[5], rng, params, episode, DT), clean[5])
    single = STATIC.astype(np.float32)
    assert np.array_equal(apply_imu_noise(single, rng, params, episode, DT), single)
    assert rng.bit_generator.state == before
    assert not episode.bias.any() and not episode.turn_on_bias.any()
    assert np.array_equal(episode.matrix, np.eye(6))


# 7. Determinism ----------------------------------------------------------------------------------------------


def test_same_seed_same_output_and_different_seed_different_output():
    clean = static(500)
    a, b, c = run(NOMINAL, clean, seed=10), run(NOMINAL, clean, seed=10), run(NOMINAL, clean, seed=11)
    assert np.array_equal(a, b)
    assert not np.any(a == c)


# 8. Single-sample calls --------------------------------------------------------------------------------------


@pytest.mark.parametrize("tau", [0.0, 5.0])
def test_single_sample_calls_reproduce_one_long_call(tau):
    # The env calls apply once per step. One (n, m) draw fills row by row, so 1000 one-sample calls consume the
    # same normals as one 1000-sample call and must give the same readings (up to summation order), i.e. the
    # bias state carried in the episode continues the drift exactly.
    params = NOMINAL.replace({"gyro_bias_tau": tau, "accel_bias_tau": tau})
    clean = static(1000)
    rng = np.random.default_rng(12)
    episode = start_imu_episode(rng, params)
    singles = np.array([apply_imu_noise(row, rng, params, episode, DT) for row in clean])
    np.testing.assert_allclose(singles, run(params, clean, seed=12), rtol=1e-12, atol=1e-12)


def test_single_sample_calls_continue_the_random_walk():
    # Drift variance after N one-sample steps is K^2 N dt. 2000 episodes x 3 axes per sensor: the variance
    # estimate has sd sqrt(2 / 6000) = 1.8 %, so 10 % is 5.5 sigma; dropping the carried state would give 1 step.
    params = ImuNoise(accel_random_walk=2e-2, gyro_random_walk=1e-3)
    steps, dt = 20, 0.01
    rng = np.random.default_rng(13)
    final = []
    for _ in range(2000):
        episode = start_imu_episode(rng, params)
        for _ in range(steps):
            apply_imu_noise(STATIC, rng, params, episode, dt)
        final.append(episode.bias.copy())
    var = np.array(final).reshape(-1, 2, 3).transpose(1, 0, 2).reshape(2, -1).var(axis=1)
    k = np.array([params.accel_random_walk, params.gyro_random_walk])
    np.testing.assert_allclose(var, k**2 * steps * dt, rtol=0.10)


# 9. Validation -----------------------------------------------------------------------------------------------


def test_bad_parameters_raise_naming_the_field():
    with pytest.raises(ValueError, match=r"imu\.gyro_noise_density"):
        ImuNoise(gyro_noise_density=-1e-3)
    with pytest.raises(ValueError, match=r"imu\.accel_range"):
        ImuNoise.from_dict({"accel_range": 0.5})
    with pytest.raises(ValueError, match=r"imu\.scale_sigma"):
        NOMINAL.replace({"scale_sigma": float("nan")})


def test_bad_inputs_raise():
    rng = np.random.default_rng(14)
    episode = start_imu_episode(rng, NOMINAL)
    with pytest.raises(ValueError, match="dt"):
        apply_imu_noise(STATIC, rng, NOMINAL, episode, 0.0)
    with pytest.raises(ValueError, match=r"\(6,\)"):
        apply_imu_noise(np.zeros(3), rng, NOMINAL, episode, DT)
