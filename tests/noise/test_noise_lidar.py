"""LIDAR noise statistics against their parameters (pure functions, no simulator)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.noise.lidar import (
    LidarEpisode,
    LidarNoise,
    angle_offsets,
    apply_lidar_noise,
    start_lidar_episode,
)

N = 200_000
MIN, MAX = 0.12, 30.0


def noisy(ranges, seed=0, episode=None, **params):
    p = LidarNoise(**params)
    return apply_lidar_noise(ranges, np.random.default_rng(seed), p, episode or LidarEpisode(), MIN, MAX)


def binomial_tolerance(p: float, n: int) -> float:
    """Five standard deviations of a rate estimated from n Bernoulli(p) trials (a false alarm every ~3.5e6 runs)."""
    return 5.0 * math.sqrt(p * (1.0 - p) / n)


@pytest.mark.parametrize("r", [0.5, 5.0, 20.0])
def test_range_sigma_is_the_larger_of_constant_and_proportional(r):
    out = noisy(np.full(N, r), range_sigma=0.01, range_sigma_frac=0.002)
    expected = max(0.01, 0.002 * r)
    # the sample std of N normals has relative standard error 1/sqrt(2N) = 0.16%: 5% is 30 standard errors
    assert abs(out.std() / expected - 1.0) < 0.05
    assert abs(out.mean() - r) < 5 * expected / math.sqrt(N)


def test_per_episode_bias_is_uniform_within_its_bound():
    params = LidarNoise(bias_m=0.03, bias_frac=0.01)
    rng = np.random.default_rng(1)
    r = 6.0  # bound = max(0.03, 0.06) = 0.06 m
    biases = np.array([
        apply_lidar_noise(np.array([r]), rng, params, start_lidar_episode(rng, params), MIN, MAX)[0] - r
        for _ in range(20_000)
    ])
    bound = 0.06
    assert np.abs(biases).max() <= bound + 1e-12
    # U(-b, b) has std b/sqrt(3); 20,000 draws estimate it to 0.6%, so 5% is generous
    assert abs(biases.std() / (bound / math.sqrt(3)) - 1.0) < 0.05
    assert abs(biases.mean()) < 5 * bound / math.sqrt(3) / math.sqrt(biases.size)


def test_bias_is_constant_within_an_episode():
    episode = LidarEpisode(bias_u=0.5)
    out = noisy(np.array([1.0, 2.0, 10.0]), episode=episode, bias_m=0.02, bias_frac=0.01)
    np.testing.assert_allclose(out, [1.01, 2.01, 10.05])


def test_dropout_rate_matches_its_probability_and_reports_no_return():
    out = noisy(np.full(N, 2.0), dropout_prob=0.1)
    dropped = out == MAX
    assert abs(dropped.mean() - 0.1) < binomial_tolerance(0.1, N)
    inf = noisy(np.full(N, 2.0), dropout_prob=0.1, no_return="inf")
    np.testing.assert_array_equal(np.isinf(inf), dropped)  # same seed, same beams


def test_spurious_returns_are_short_and_at_their_rate():
    out = noisy(np.full(N, 5.0), spurious_prob=0.02)
    short = out < 5.0
    assert abs(short.mean() - 0.02) < binomial_tolerance(0.02, N)
    assert out[short].min() >= MIN
    # uniform on [MIN, 5]: its mean is the midpoint
    assert abs(out[short].mean() - (MIN + 5.0) / 2) < 5 * (5.0 - MIN) / math.sqrt(12 * short.sum())


def test_quantisation_is_exact():
    r = np.random.default_rng(3).uniform(0.2, 20.0, N)
    out = noisy(r, quantization=0.015)
    steps = out / 0.015
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)
    assert np.abs(out - r).max() <= 0.0075 + 1e-12


def test_readings_outside_the_window_are_no_returns():
    r = np.array([0.05, 0.2, 3.0, 3.6, MAX])
    out = noisy(r, max_range=3.5, min_range=0.15, no_return="inf")
    np.testing.assert_array_equal(out, [math.inf, 0.2, 3.0, math.inf, math.inf])


def test_no_return_stays_a_no_return_whatever_the_noise():
    out = noisy(np.full(1000, MAX), range_sigma=0.5, spurious_prob=0.5, bias_m=0.1)
    np.testing.assert_array_equal(out, MAX)


def test_angular_jitter_std():
    offsets = angle_offsets((N,), np.random.default_rng(4), LidarNoise(angular_jitter=0.0087))
    assert abs(offsets.std() / 0.0087 - 1.0) < 0.05
    assert angle_offsets((N,), np.random.default_rng(4), LidarNoise()) is None


def test_clean_params_return_the_reading_and_draw_nothing():
    rng = np.random.default_rng(5)
    before = rng.bit_generator.state
    r = np.linspace(0.2, 29.0, 50)
    assert apply_lidar_noise(r, rng, LidarNoise(), start_lidar_episode(rng, LidarNoise()), MIN, MAX) is r
    assert rng.bit_generator.state == before


def test_same_seed_same_noise_different_seed_different_noise():
    r = np.linspace(0.2, 10.0, 360)
    params = dict(range_sigma=0.01, dropout_prob=0.05, spurious_prob=0.01, quantization=0.001)
    np.testing.assert_array_equal(noisy(r, seed=7, **params), noisy(r, seed=7, **params))
    assert not np.array_equal(noisy(r, seed=7, **params), noisy(r, seed=8, **params))


@pytest.mark.parametrize(
    "params, pattern",
    [
        ({"range_sigma": -0.1}, r"lidar\.range_sigma must be a number in \[0\.0, 1\.0\] m"),
        ({"dropout_prob": 1.5}, r"lidar\.dropout_prob must be a number in \[0\.0, 1\.0\]"),
        ({"quantization": float("nan")}, r"lidar\.quantization"),
        ({"no_return": "zero"}, r"lidar\.no_return must be one of \('max', 'inf'\)"),
    ],
)
def test_bad_parameters_name_the_field_and_range(params, pattern):
    with pytest.raises(ValueError, match=pattern):
        LidarNoise(**params)
