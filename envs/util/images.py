"""Whole images on plain numpy arrays, no simulator: a square image resampled onto another grid, and frames laid
side by side above their labels."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

LABEL_PX = 24  # height of the label bar under each frame of a strip


def resample(image: np.ndarray, size: int) -> np.ndarray:
    """A square ``image`` at the pixel centres of a ``size`` x ``size`` grid over the same field of view (each the
    nearest pixel's value)."""
    index = ((np.arange(size) + 0.5) * image.shape[0] / size).astype(int)
    return image[np.ix_(index, index)]


def labelled_strip(frames: dict[str, np.ndarray]) -> Image.Image:
    """The frames (H, W, 3 uint8, all one size) side by side, each above a bar :data:`LABEL_PX` high with its
    label."""
    height, width = next(iter(frames.values())).shape[:2]
    strip = Image.new("RGB", (width * len(frames), height + LABEL_PX), (250, 250, 250))
    draw = ImageDraw.Draw(strip)
    try:
        font = ImageFont.load_default(size=16)
    except TypeError:  # pillow < 10.1: one bitmap size
        font = ImageFont.load_default()
    for i, (label, frame) in enumerate(frames.items()):
        strip.paste(Image.fromarray(frame), (i * width, 0))
        left, top, right, bottom = draw.textbbox((0, 0), label, font=font)
        draw.text((i * width + (width - right + left) / 2, height + (LABEL_PX - bottom + top) / 2 - top), label,
                  fill=(30, 30, 30), font=font)
    return strip
