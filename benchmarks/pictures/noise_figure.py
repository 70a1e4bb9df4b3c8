"""Picture of the noise profiles: one LIDAR scan and one depth image, clean and under each profile.

Every profile sees the same layout (a seed gives the same layouts under every profile) from the same pose.

    python -m benchmarks.pictures.noise_figure    # writes docs/noise_profiles.png
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import clutter_gym  # noqa: E402, F401  (registers the envs)
from clutter_gym.noise.profiles import PROFILE_NAMES  # noqa: E402


def capture(profile: str, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(beam angles, LIDAR ranges, depth image, lidar_range) a few steps into an episode, robot at rest."""
    env = gym.make("ClutterNav-v1", sensors=("lidar", "camera"), camera_modes=("depth",), noise=profile)
    env.reset(seed=seed)
    for _ in range(3):  # past any latency, so every profile shows a reading taken at the same pose
        obs, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
    lidar = env.unwrapped.sensors[0]
    out = lidar.config.angles, info["lidar_ranges"], obs["camera_depth"], lidar.config.max_range
    env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--out", default="docs/noise_profiles.png")
    args = parser.parse_args()

    shots = {name: capture(name, args.seed) for name in PROFILE_NAMES}
    fig = plt.figure(figsize=(3.2 * len(shots), 6.4))
    angles, clean_ranges, _, max_range = shots["none"]
    for col, (name, (_, ranges, depth, _)) in enumerate(shots.items()):
        ax = fig.add_subplot(2, len(shots), col + 1, projection="polar")
        if name != "none":
            ax.plot(np.append(angles, angles[0]), np.append(clean_ranges, clean_ranges[0]), color="0.7", lw=1)
        shown = np.minimum(ranges, max_range)  # an inf no-return is drawn at the maximum range
        ax.scatter(angles, shown, s=6, color="tab:blue" if name == "none" else "tab:red")
        ax.set_ylim(0, max_range)
        ax.set_title(f"{name}: LIDAR (m)", fontsize=10)
        ax.tick_params(labelsize=7)
        ax = fig.add_subplot(2, len(shots), len(shots) + col + 1)
        image = ax.imshow(np.where(depth > 0, depth, np.nan), cmap="viridis", vmin=0, vmax=4)
        ax.set_title(f"{name}: depth (m, white = no data)", fontsize=10)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(image, ax=fig.axes[1::2], shrink=0.6, location="bottom")
    fig.suptitle(f"ClutterNav-v1 seed {args.seed}: clean (grey) and noisy readings at the same pose", fontsize=11)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".png", dir=out.parent)  # atomic: a complete PNG or none
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
