"""The README's picture of the envs (``python -m benchmarks.pictures.env_pictures``): the committed file is one
small labelled frame per env, laid out side by side above their labels."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from benchmarks.pictures.env_pictures import LABEL_PX, labelled_strip
from clutter_gym import ENV_IDS

PICTURE = Path(__file__).resolve().parents[1] / "docs" / "images" / "envs.png"


def test_the_committed_picture_is_one_small_labelled_frame_per_env():
    image = Image.open(PICTURE)
    assert image.size == (320 * len(ENV_IDS), 240 + LABEL_PX)
    assert PICTURE.stat().st_size < 150_000


def test_the_strip_puts_the_frames_side_by_side_above_their_labels():
    frames = {"A-v0": np.full((240, 320, 3), 40, np.uint8), "B-v0": np.full((240, 320, 3), 200, np.uint8)}
    strip = np.asarray(labelled_strip(frames))
    assert strip.shape == (240 + LABEL_PX, 640, 3)
    assert np.all(strip[:240, :320] == 40) and np.all(strip[:240, 320:] == 200)
    label = strip[240:, :320]
    assert (label < 128).any() and (label > 200).mean() > 0.5  # dark text on a light bar
