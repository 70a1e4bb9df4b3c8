"""The README's picture of the envs: one mid-episode ``rgb_array`` frame of each env's scripted demo policy (the one
``clutter-gym demo`` runs), labelled with its env id, side by side.

Each episode is run twice on its seed: once to its end, to learn its length, then again to the chosen fraction of
it, where the frame is taken (the robot's trail then shows the way so far).

    python -m benchmarks.pictures.env_pictures    # writes docs/images/envs.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import numpy as np
from PIL import Image, ImageDraw, ImageFont

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.cli import DEMOS
from clutter_gym.util.atomic import atomic_path

#: Each env's picture: the seed (an episode the demo policy finishes at the goal) and how far into the episode.
SHOTS = {"ClutterNav-v1": (0, 0.75), "ClutterReach-v1": (1, 0.5), "ClutterFly-v1": (2, 0.6)}
MAX_STEPS = 600
LABEL_PX = 24  # height of the label bar under each frame


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


def _rollout(env: gym.Env, seed: int, make_policy, steps: int) -> int:
    """Reset on ``seed`` and step the policy ``steps`` times or to the episode's end; the steps taken."""
    obs, _ = env.reset(seed=seed)
    policy = make_policy(env)
    for taken in range(steps):
        obs, _, terminated, truncated, _ = env.step(policy(obs))
        if terminated or truncated:
            return taken + 1
    return steps


def mid_episode_frame(env_id: str, seed: int, fraction: float = 0.5) -> np.ndarray:
    """The ``rgb_array`` frame ``fraction`` of the way through the demo policy's episode on ``seed``."""
    kwargs, make_policy = DEMOS[env_id].kwargs, DEMOS[env_id].make_policy
    env = gym.make(env_id, render_mode="rgb_array", **kwargs)
    try:
        length = _rollout(env, seed, make_policy, MAX_STEPS)
        _rollout(env, seed, make_policy, max(1, round(fraction * length)))
        return env.render()
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="docs/images/envs.png")
    args = parser.parse_args()
    strip = labelled_strip({env_id: mid_episode_frame(env_id, *shot) for env_id, shot in SHOTS.items()})
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        # an adaptive palette keeps the file small; the flat-shaded frames lose nothing visible
        strip.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(tmp, "PNG",
                                                                                                   optimize=True)
    print(f"wrote {out} ({out.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    main()
