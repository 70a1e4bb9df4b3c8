"""The camera-resolution benchmark (``python -m benchmarks.fidelity.camera_resolution``) compares a depth image with
a larger reference by resampling it onto the reference's grid at its pixel centres."""

from __future__ import annotations

import numpy as np

from benchmarks.fidelity.camera_resolution import resample


def test_resample_samples_pixel_centres():
    depth = np.arange(16.0).reshape(4, 4)
    assert np.array_equal(resample(depth, 4), depth)
    assert np.array_equal(resample(depth, 2), depth[np.ix_([1, 3], [1, 3])])
    assert np.array_equal(resample(depth, 8), np.repeat(np.repeat(depth, 2, axis=0), 2, axis=1))
