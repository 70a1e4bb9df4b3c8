"""Episode videos: GIF (Pillow, always available) or MP4 (ffmpeg through the imageio-ffmpeg wheel)."""

from __future__ import annotations

from pathlib import Path

import imageio.v2 as imageio
import numpy as np

from clutter_gym.util.atomic import atomic_path

VIDEO_SUFFIXES = (".gif", ".mp4")


def write_video(path: str | Path, frames: list[np.ndarray], fps: float) -> Path:
    """Write ``frames`` (H, W, 3 uint8) to ``path``; the format follows the suffix; the file appears whole or not
    at all.

    Raises:
        ValueError: the suffix is not .gif or .mp4, or there are no frames.
        RuntimeError: .mp4 asked for without the imageio-ffmpeg package.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ValueError(f"video path must end in one of {VIDEO_SUFFIXES}, got {str(path)!r}")
    if not frames:
        raise ValueError("no frames to write")
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError as exc:
            raise RuntimeError("writing .mp4 needs the imageio-ffmpeg package (pip install imageio-ffmpeg); "
                               "or ask for a .gif") from exc
    with atomic_path(path) as tmp:
        if suffix == ".gif":
            imageio.mimsave(tmp, frames, format="GIF", duration=1000.0 / fps, loop=0)
        else:
            # 16-pixel macro blocks: pad rather than let ffmpeg resize (and warn about) odd frame sizes.
            imageio.mimsave(tmp, frames, format="FFMPEG", fps=fps, macro_block_size=16)
    return path
