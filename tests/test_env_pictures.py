"""The README's picture of the envs (``python -m benchmarks.pictures.env_pictures``): the committed file is one
small labelled frame per env."""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from clutter_gym import ENV_IDS
from clutter_gym.util.images import LABEL_PX

PICTURE = Path(__file__).resolve().parents[1] / "docs" / "images" / "envs.png"


def test_the_committed_picture_is_one_small_labelled_frame_per_env():
    image = Image.open(PICTURE)
    assert image.size == (320 * len(ENV_IDS), 240 + LABEL_PX)
    assert PICTURE.stat().st_size < 150_000
