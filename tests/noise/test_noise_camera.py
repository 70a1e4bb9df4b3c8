"""Camera noise: lens distortion round trips and analytic values, and the statistics of every RGB / depth stage.

Fixed seeds throughout. Statistical tolerances are stated next to each check with the margin they leave (standard
errors for the sample sizes used), so a failure means a model error, not bad luck.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage, stats

from clutter_gym.noise.camera import (
    DepthEpisode,
    DepthNoise,
    RgbEpisode,
    RgbNoise,
    apply_depth_noise,
    apply_rgb_noise,
    standard_normal,
    start_depth_episode,
    start_rgb_episode,
)
from clutter_gym.noise.distortion import (
    Distortion,
    Intrinsics,
    distort_normalized,
    distortion_remap,
    remap,
    undistort_normalized,
)

REALISTIC = Distortion(k1=-0.28, k2=0.07, p1=1e-3, p2=-5e-4, k3=0.0)
ZERO = Distortion()


def cam(width: int, height: int | None = None, vfov_deg: float = 60.0) -> Intrinsics:
    return Intrinsics.from_fov(width, width if height is None else height, math.radians(vfov_deg))


def remap_for(intr: Intrinsics, k) -> tuple[np.ndarray, np.ndarray]:
    return distortion_remap(intr.width, intr.height, intr.fx, intr.fy, intr.cx, intr.cy, k)


# ------------------------------------------------------------------------------------------------ distortion
def test_intrinsics_from_fov_pixel_centre_convention():
    intr = cam(84, 64, 60.0)
    assert intr.fx == intr.fy == pytest.approx(32.0 / math.tan(math.radians(30.0)))
    assert (intr.cx, intr.cy) == (41.5, 31.5)
    # the outer edge of the top row (v = -0.5) is at half the vertical FOV
    assert math.atan2(intr.cy + 0.5, intr.fy) == pytest.approx(math.radians(30.0))
    with pytest.raises(ValueError):
        Intrinsics.from_fov(84, 84, 0.0)


def test_distortion_round_trips_over_the_image():
    intr = cam(640, 480, 70.0)  # normalised radius up to ~0.88 at the corners
    v, u = np.mgrid[-0.5 : intr.height - 0.5 : 61j, -0.5 : intr.width - 0.5 : 81j]
    x, y = (u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy
    xd, yd = distort_normalized(x, y, REALISTIC)
    assert np.max(np.hypot(xd - x, yd - y)) > 0.05  # the distortion is far from negligible here
    xu, yu = undistort_normalized(xd, yd, REALISTIC)
    assert np.max(np.abs(xu - x)) < 1e-9 and np.max(np.abs(yu - y)) < 1e-9
    xu, yu = undistort_normalized(x, y, REALISTIC)
    xr, yr = distort_normalized(xu, yu, REALISTIC)
    assert np.max(np.abs(xr - x)) < 1e-9 and np.max(np.abs(yr - y)) < 1e-9


def test_zero_distortion_is_the_identity_exactly():
    x, y = np.meshgrid(np.linspace(-1, 1, 17), np.linspace(-0.7, 0.7, 13))
    for fn in (distort_normalized, undistort_normalized):
        xo, yo = fn(x, y, ZERO)
        assert np.array_equal(xo, x) and np.array_equal(yo, y)


def test_distortion_analytic_values():
    r = np.linspace(0.0, 0.8, 9)
    theta = 0.7
    x, y = r * math.cos(theta), r * math.sin(theta)
    xd, yd = distort_normalized(x, y, Distortion(k1=-0.2))  # pure k1: r_d = r (1 + k1 r^2), same direction
    np.testing.assert_allclose(np.hypot(xd, yd), r * (1 - 0.2 * r**2), rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.arctan2(yd[1:], xd[1:]), theta, atol=1e-15)
    # pure tangential on the y axis (x = 0): xd = p2 y^2, yd = y + 3 p1 y^2
    y = np.linspace(-0.5, 0.5, 11)
    xd, yd = distort_normalized(np.zeros_like(y), y, Distortion(p1=0.01, p2=-0.02))
    np.testing.assert_allclose(xd, -0.02 * y**2, atol=1e-16)
    np.testing.assert_allclose(yd, y + 0.03 * y**2, atol=1e-16)


def test_undistort_beyond_the_fold_is_nan():
    # r_d = r (1 - r^2) peaks at r_d = 0.385: no ideal point distorts to r_d = 0.5
    x, y = undistort_normalized(np.array([0.1, 0.5]), np.array([0.0, 0.0]), Distortion(k1=-1.0))
    assert np.isfinite(x[0]) and np.isnan(x[1]) and np.isnan(y[1])


def test_remap_without_distortion_returns_the_image():
    rng = np.random.default_rng(0)
    intr = cam(20, 14)
    maps = remap_for(intr, ZERO)
    rgb = rng.integers(0, 256, (14, 20, 3), dtype=np.uint8)
    depth = rng.uniform(0.3, 5.0, (14, 20))
    for order in (0, 1):
        for fill in (None, 0.0):
            out = remap(rgb, maps, order=order, fill=fill)
            assert out.dtype == np.uint8 and np.array_equal(out, rgb)
            out = remap(depth, maps, order=order, fill=fill)
            assert out.dtype == depth.dtype and np.array_equal(out, depth)


def test_remap_is_cached_and_read_only():
    intr = cam(32)
    maps = remap_for(intr, REALISTIC)
    assert remap_for(intr, list(REALISTIC))[0] is maps[0]
    with pytest.raises(ValueError):
        maps[0][0, 0] = 1.0


def test_bilinear_remap_matches_scipy_map_coordinates():
    rng = np.random.default_rng(1)
    intr = cam(48, 36)
    maps = remap_for(intr, REALISTIC)
    image = rng.uniform(0.0, 1.0, (36, 48))
    ours = remap(image, maps, order=1)
    ref = ndimage.map_coordinates(image, np.stack(maps), order=1, mode="nearest")
    np.testing.assert_allclose(ours, ref, atol=1e-6)  # weights are float32


def test_barrel_distortion_bends_lines_outward_and_pulls_corners_in():
    intr = cam(84)
    barrel = Distortion(k1=-0.28, k2=0.07)  # without k2, k1 = -0.28 folds before the corners of this 60 deg camera
    maps = remap_for(intr, barrel)
    # a ray near a corner of the distorted image comes from farther out in the ideal image
    rows, cols = maps
    assert rows[2, 2] < 2 and cols[2, 2] < 2
    assert abs(rows[42, 42] - 42) < 0.6  # and the centre barely moves
    # a straight bright row in the ideal image: in the distorted image its ends are nearer the centre row than its
    # middle, i.e. it bows outward (barrel), and its middle sits where the analytic model puts it
    ideal = np.zeros((84, 84))
    ideal[12, :] = 1.0
    out = remap(ideal, maps, order=1, fill=0.0)
    peak = np.array([np.average(np.arange(84), weights=out[:, c]) for c in range(10, 74)])
    assert peak[0] > peak[32] + 1.0 and peak[-1] > peak[32] + 1.0
    xd, yd = distort_normalized(0.0, (12 - intr.cy) / intr.fy, barrel)
    assert peak[31:33].mean() == pytest.approx(yd * intr.fy + intr.cy, abs=0.2)
    # and a single bright pixel near the corner appears closer to the centre
    ideal = np.zeros((84, 84))
    ideal[8, 8] = 1.0
    out = remap(ideal, maps, order=1, fill=0.0)
    r, c = np.unravel_index(np.argmax(out), out.shape)
    assert r > 8 and c > 8


def test_depth_distortion_uses_nearest_samples_only():
    z = np.where(np.arange(84)[None, :] < 40, 1.0, 3.0) * np.ones((84, 1))
    params = DepthNoise(k1=-0.28, k2=0.07)
    out = apply_depth_noise(z, np.random.default_rng(0), params, DepthEpisode(), cam(84))
    assert set(np.unique(out)) <= {0.0, 1.0, 3.0}  # no flying pixels between the two surfaces
    assert out[0, 0] == 0.0 and out[42, 20] == 1.0 and out[42, 70] == 3.0  # off-field corner rays read no data


# ------------------------------------------------------------------------------------------------ depth
@pytest.mark.parametrize("z", [1.0, 3.0])
def test_depth_axial_noise_std_and_mean(z):
    params = DepthNoise(sigma_c0=0.001, sigma_c2=0.0047, sigma_z0=0.4)
    n = 512
    out = apply_depth_noise(np.full((n, n), z), np.random.default_rng(2), params, DepthEpisode(), cam(n))
    sigma = 0.001 + 0.0047 * (z - 0.4) ** 2
    err = out.astype(np.float64) - z
    assert abs(err.std() / sigma - 1) < 0.05  # std error of the sample std: 1 / sqrt(2 n^2) = 0.14 %
    assert abs(err.mean()) < 5 * sigma / n  # 5 standard errors of the mean


def test_depth_bias_is_uniform_per_episode():
    params = DepthNoise(bias_m=0.011, bias_frac=0.001)
    rng = np.random.default_rng(3)
    intr = cam(2, 1)
    depth = np.array([[1.0, 4.0]])
    biases = []
    for _ in range(5000):
        episode = start_depth_episode(rng, params)
        biases.append(apply_depth_noise(depth, rng, params, episode, intr)[0].astype(np.float64) - depth[0])
    biases = np.array(biases)
    for j, z in enumerate(depth[0]):
        half = 0.011 + 0.001 * z
        assert np.all(np.abs(biases[:, j]) <= half + 1e-6)  # float32 output
        assert abs(biases[:, j].std() / (half / math.sqrt(3)) - 1) < 0.05  # std error 0.63 % here
        assert stats.kstest(biases[:, j], stats.uniform(-half, 2 * half).cdf).pvalue > 1e-3
    # one draw per episode: every pixel of an episode shares u
    np.testing.assert_allclose(biases[:, 0] / 0.012, biases[:, 1] / 0.015, atol=1e-4)


def test_depth_constant_quantisation_is_exact():
    z = np.linspace(0.3, 6.0, 128 * 128).reshape(128, 128)
    params = DepthNoise(sigma_c2=0.0047, quantization_m=0.001)
    out = apply_depth_noise(z, np.random.default_rng(4), params, DepthEpisode(), cam(128)).astype(np.float64)
    steps = np.rint(out / 0.001)
    assert np.array_equal(out, (steps * 0.001).astype(np.float32).astype(np.float64))


def test_depth_disparity_quantisation():
    c2 = 0.00285
    z = np.linspace(0.5, 6.0, 128 * 128)  # ramp steps finer than the level spacing: every level is hit
    params = DepthNoise(quantization_c2=c2)
    out = apply_depth_noise(z.reshape(128, 128), np.random.default_rng(5), params, DepthEpisode(), cam(128))
    out = out.ravel().astype(np.float64)
    levels = 1.0 / (c2 * out)  # the output depths sit on the inverse-depth levels 1 / (n c2)
    assert np.max(np.abs(levels - np.rint(levels))) < 1e-3
    assert np.all(np.diff(out) >= 0)  # a quantiser: monotone, piecewise constant
    step = c2 * z**2  # the level spacing at z; exact bound of inverse-depth rounding (1 + O(step / z) over step / 2)
    assert np.all(np.abs(out - z) <= (step / 2) / (1 - step / (2 * z)) + 1e-6)
    assert np.max(np.abs(out - z) / (step / 2)) > 0.99  # and the bound is tight
    assert len(np.unique(out)) == pytest.approx(1 / (c2 * 0.5) - 1 / (c2 * 6.0), abs=2)


def test_depth_random_holes_rate():
    n = 512
    params = DepthNoise(hole_prob=0.1)
    out = apply_depth_noise(np.full((n, n), 2.0), np.random.default_rng(6), params, DepthEpisode(), cam(n))
    rate = np.mean(out == 0.0)
    assert abs(rate - 0.1) < 5 * math.sqrt(0.1 * 0.9 / n**2)
    assert np.all(out[out != 0] == 2.0)


def test_depth_edge_holes_only_at_discontinuities():
    n = 256
    cols = np.arange(n)[None, :] * np.ones((n, 1))
    z = np.where(cols < 128, 1.0, 2.0) + 0.01 * cols / n  # step edge between columns 127 and 128, gentle slope
    rng = np.random.default_rng(7)
    out = apply_depth_noise(z, rng, DepthNoise(edge_hole_prob=1.0), DepthEpisode(), cam(n))
    holes = out == 0.0
    assert np.all(holes[:, 127:129]) and not np.any(np.delete(holes, [127, 128], axis=1))
    out = apply_depth_noise(z, rng, DepthNoise(edge_hole_prob=0.5), DepthEpisode(), cam(n))
    holes = out == 0.0
    assert not np.any(np.delete(holes, [127, 128], axis=1))
    assert abs(holes[:, 127:129].mean() - 0.5) < 5 * math.sqrt(0.25 / (2 * n))
    # a threshold above the step: no discontinuity, no holes
    out = apply_depth_noise(z, rng, DepthNoise(edge_hole_prob=1.0, edge_threshold_m=1.5), DepthEpisode(), cam(n))
    assert np.all(out > 0)


def test_depth_range_limits_and_no_data_inputs():
    z = np.linspace(0.05, 12.0, 64 * 64).reshape(64, 64)
    params = DepthNoise(min_depth=0.28, max_depth=10.0)
    out = apply_depth_noise(z, np.random.default_rng(8), params, DepthEpisode(), cam(64))
    inside = (z >= 0.28) & (z <= 10.0)
    assert np.all(out[~inside] == 0.0) and np.array_equal(out[inside], z[inside].astype(np.float32))
    noisy = DepthNoise(sigma_c2=0.01, min_depth=0.28, max_depth=10.0)
    out = apply_depth_noise(z, np.random.default_rng(8), noisy, DepthEpisode(), cam(64))
    assert np.all((out == 0) | ((out >= 0.28) & (out <= 10.0)))
    bad = z.copy()
    bad[0, :4] = (0.0, -1.0, np.nan, np.inf)
    out = apply_depth_noise(bad, np.random.default_rng(8), DepthNoise(sigma_c0=0.01), DepthEpisode(), cam(64))
    assert np.all(out[0, :4] == 0.0) and np.all(out[1:] > 0)


def test_depth_lateral_jitter_statistics():
    # depth = column index (mm): the output minus the input is the column offset of the sample, exactly
    n = 384
    cols = np.arange(n)[None, :] * np.ones((n, 1))
    z = 1.0 + 0.001 * cols
    sigma = 0.8
    params = DepthNoise(lateral_sigma_px=sigma)
    out = apply_depth_noise(z, np.random.default_rng(9), params, DepthEpisode(), cam(n)).astype(np.float64)
    offsets = (out - z)[:, 8:-8] / 0.001  # away from the clamped borders
    assert np.max(np.abs(offsets - np.rint(offsets))) < 1e-3  # whole pixels: no mixed depths
    k = np.arange(-10, 11)
    p = stats.norm.cdf((k + 0.5) / sigma) - stats.norm.cdf((k - 0.5) / sigma)  # round(sigma n)
    expected_var = np.sum(p * k**2)
    assert abs(offsets.var() / expected_var - 1) < 0.05
    assert abs(offsets.mean()) < 5 * math.sqrt(expected_var / offsets.size)


# ------------------------------------------------------------------------------------------------ RGB
@pytest.mark.parametrize("read_sigma", [2.0, 5.0])
def test_rgb_read_noise_std(read_sigma):
    # Rounding to whole DN adds 1/12 DN^2 of variance (Sheppard); for sigma >= 2 DN that correction is exact to
    # exp(-2 pi^2 sigma^2) ~ 1e-34, so sqrt(var - 1/12) estimates sigma without rounding bias.
    n = 512
    grey = np.full((n, n, 3), 128, dtype=np.uint8)
    params = RgbNoise(read_sigma=read_sigma)
    out = apply_rgb_noise(grey, np.random.default_rng(10), params, RgbEpisode(), cam(n)).astype(np.float64)
    assert abs(math.sqrt(out.var() - 1 / 12) / read_sigma - 1) < 0.05  # std error 0.08 %
    assert abs(out.mean() - 128) < 5 * read_sigma / math.sqrt(out.size)


@pytest.mark.parametrize("level", [10, 128, 180])
def test_rgb_shot_noise_variance(level):
    # N = 255 electrons at full scale: one electron is one DN, so the normalised variance s / N is level DN^2.
    # Level 10 (10 e-) takes the exact Poisson path: integer outputs, no rounding; the others the Gaussian one.
    n = 512
    image = np.full((n, n, 3), level, dtype=np.uint8)
    params = RgbNoise(shot_electrons=255.0)
    out = apply_rgb_noise(image, np.random.default_rng(11), params, RgbEpisode(), cam(n)).astype(np.float64)
    var_norm = (out / 255.0).var() - (0 if level < 30 else 1 / 12 / 255**2)
    s = level / 255.0
    assert abs(var_norm / (s / 255.0) - 1) < 0.05  # std error of the variance ~0.16 %
    assert abs(out.mean() - level) < 5 * math.sqrt(level / out.size)


def test_rgb_shot_noise_at_high_full_well_and_with_read_noise():
    n = 512
    image = np.full((n, n, 3), 128, dtype=np.uint8)
    params = RgbNoise(shot_electrons=2000.0, read_sigma=2.0)
    out = apply_rgb_noise(image, np.random.default_rng(12), params, RgbEpisode(), cam(n)).astype(np.float64)
    expected = (128 / 255) / 2000 * 255**2 + 4.0  # shot + read, DN^2
    assert abs((out.var() - 1 / 12) / expected - 1) < 0.05


def test_rgb_episode_gains():
    rng = np.random.default_rng(13)
    params = RgbNoise(gain_sigma=0.05)
    intr = cam(8)
    image = np.full((8, 8, 3), 100, dtype=np.uint8)
    ratios = []
    for _ in range(4000):
        episode = start_rgb_episode(rng, params)
        assert episode.gains[0] == episode.gains[1] == episode.gains[2]
        out = apply_rgb_noise(image, rng, params, episode, intr)
        assert np.all(out == np.rint(100 * np.float32(episode.gains[0])))
        ratios.append(out.mean() / 100)
    assert abs(np.std(ratios) / 0.05 - 1) < 0.05  # std error 1.1 %; rounding adds 0.3 % in quadrature
    assert abs(np.mean(ratios) - 1) < 5 * 0.05 / math.sqrt(4000)
    colour = np.array([start_rgb_episode(rng, RgbNoise(color_sigma=0.03)).gains for _ in range(4000)])
    assert np.all(np.abs(colour.std(axis=0) / 0.03 - 1) < 0.05)
    assert abs(np.corrcoef(colour.T)[0, 1]) < 0.06  # independent channels


def test_rgb_lens_distortion_changes_geometry_only():
    intr = cam(84)
    rng = np.random.default_rng(14)
    image = rng.integers(0, 256, (84, 84, 3), dtype=np.uint8)
    params = RgbNoise(k1=-0.1)
    state = rng.bit_generator.state
    out = apply_rgb_noise(image, rng, params, RgbEpisode(), intr)
    assert rng.bit_generator.state == state  # distortion alone draws nothing
    assert np.array_equal(out, remap(image, remap_for(intr, params.distortion), order=1))


def test_standard_normal_table():
    draws = standard_normal(np.random.default_rng(15), 10**6).astype(np.float64)
    assert abs(draws.mean()) < 5e-3 and abs(draws.std() - 1) < 5e-3
    assert stats.kstest(draws[:200_000], "norm").pvalue > 1e-3


# ------------------------------------------------------------------------------------------------ shared
ALL_RGB = RgbNoise(read_sigma=1.8, shot_electrons=5000, gain_sigma=0.02, color_sigma=0.01, k1=-0.05, p1=1e-3)
ALL_DEPTH = DepthNoise(
    sigma_c0=0.0012,
    sigma_c2=0.0047,
    sigma_z0=0.4,
    bias_m=0.011,
    bias_frac=0.001,
    quantization_c2=0.00285,
    quantization_m=0.001,
    lateral_sigma_px=0.8,
    hole_prob=0.05,
    edge_hole_prob=0.5,
    min_depth=0.28,
    max_depth=10.0,
    k1=-0.05,
)


def _scene(n: int = 84) -> tuple[np.ndarray, np.ndarray]:
    yy, xx = np.mgrid[0:n, 0:n]
    rgb = np.stack([(xx * 3) % 256, (yy * 3) % 256, np.full_like(xx, 128)], -1).astype(np.uint8)
    depth = np.where(xx < 40, 1.5, 3.0) + 0.01 * yy
    return rgb, depth


def _run(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rgb, depth = _scene()
    rng = np.random.default_rng(seed)
    intr = cam(84)
    rgb_ep, depth_ep = start_rgb_episode(rng, ALL_RGB), start_depth_episode(rng, ALL_DEPTH)
    return apply_rgb_noise(rgb, rng, ALL_RGB, rgb_ep, intr), apply_depth_noise(depth, rng, ALL_DEPTH, depth_ep, intr)


def test_same_seed_same_images_and_different_seed_differs():
    a, b, c = _run(0), _run(0), _run(1)
    assert a[0].dtype == np.uint8 and a[1].dtype == np.float32
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0]) and not np.array_equal(a[1], c[1])


def test_clean_params_return_input_and_draw_nothing():
    rgb, depth = _scene()
    rng = np.random.default_rng(16)
    state = rng.bit_generator.state
    intr = cam(84)
    rgb_ep, depth_ep = start_rgb_episode(rng, RgbNoise()), start_depth_episode(rng, DepthNoise())
    assert (rgb_ep, depth_ep) == (RgbEpisode(), DepthEpisode())
    out_rgb = apply_rgb_noise(rgb, rng, RgbNoise(), rgb_ep, intr)
    out_depth = apply_depth_noise(depth, rng, DepthNoise(), depth_ep, intr)
    assert out_rgb.dtype == rgb.dtype and np.array_equal(out_rgb, rgb)
    assert out_depth.dtype == depth.dtype and np.array_equal(out_depth, depth)
    assert rng.bit_generator.state == state
    # stages without a per-episode part draw nothing at episode start either
    start_rgb_episode(rng, RgbNoise(read_sigma=2.0))
    start_depth_episode(rng, DepthNoise(sigma_c2=0.01))
    assert rng.bit_generator.state == state


def test_bad_parameters_raise_naming_the_field():
    with pytest.raises(ValueError, match=r"camera_depth\.hole_prob"):
        DepthNoise(hole_prob=1.5)
    with pytest.raises(ValueError, match=r"camera_depth\.sigma_c2"):
        DepthNoise.from_dict({"sigma_c2": -0.1})
    with pytest.raises(ValueError, match=r"camera_depth\.min_depth"):
        DepthNoise(min_depth=5.0, max_depth=3.0)
    with pytest.raises(ValueError, match=r"camera_rgb\.read_sigma"):
        RgbNoise(read_sigma=float("nan"))
    with pytest.raises(ValueError, match="unknown camera_depth"):
        DepthNoise.from_dict({"sigma": 0.1})
    with pytest.raises(ValueError, match="intrinsics"):
        apply_depth_noise(
            np.ones((10, 12)), np.random.default_rng(0), DepthNoise(hole_prob=0.1), DepthEpisode(), cam(12)
        )
