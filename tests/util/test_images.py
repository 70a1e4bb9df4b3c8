"""Whole-image helpers: resampling onto another grid at its pixel centres, frames laid out above their labels."""

from __future__ import annotations

import numpy as np

from clutter_gym.util.images import LABEL_PX, labelled_strip, resample


def test_resample_samples_pixel_centres():
    depth = np.arange(16.0).reshape(4, 4)
    assert np.array_equal(resample(depth, 4), depth)
    assert np.array_equal(resample(depth, 2), depth[np.ix_([1, 3], [1, 3])])
    assert np.array_equal(resample(depth, 8), np.repeat(np.repeat(depth, 2, axis=0), 2, axis=1))


def test_the_strip_puts_the_frames_side_by_side_above_their_labels():
    frames = {"A-v0": np.full((240, 320, 3), 40, np.uint8), "B-v0": np.full((240, 320, 3), 200, np.uint8)}
    strip = np.asarray(labelled_strip(frames))
    assert strip.shape == (240 + LABEL_PX, 640, 3)
    assert np.all(strip[:240, :320] == 40) and np.all(strip[:240, 320:] == 200)
    label = strip[240:, :320]
    assert (label < 128).any() and (label > 200).mean() > 0.5  # dark text on a light bar
