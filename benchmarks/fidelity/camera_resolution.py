"""Speed against error of the camera's image size: frame time against the depth detail a smaller image loses.

The scripted navigator drives ClutterNav-v1 with its default RGB-D camera; at every pose each size renders its
RGB-D frame (interleaved, so machine noise hits them alike) with TinyRenderer, and so does a 256x256 reference.
The error is the mean absolute difference between a size's depth image, sampled at the reference's pixel
centres (nearest pixel), and the reference depth: what the coarser grid blurs at obstacle edges. Pixels seen by
neither count as zero error; a pixel seen by one only counts its whole depth.

    python -m benchmarks.fidelity.camera_resolution
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import navigator_states, table_header
from clutter_gym.sensors.camera import Camera, CameraConfig

SIZES = (32, 48, 64, 84, 128)
REFERENCE_SIZE = 256
DEFAULT_SIZE = CameraConfig.width


def resample(image: np.ndarray, size: int) -> np.ndarray:
    """A square ``image`` at the pixel centres of a ``size`` x ``size`` grid over the same field of view (each the
    nearest pixel's value)."""
    index = ((np.arange(size) + 0.5) * image.shape[0] / size).astype(int)
    return image[np.ix_(index, index)]


def rows(steps: int = 200, seed: int = 0) -> list[dict]:
    """Per size: RGB-D frame time (us), mean absolute depth error (mm) against the reference, default flag."""
    env = gym.make("ClutterNav-v1", sensors=("lidar", "imu", "camera"))
    u = env.unwrapped
    cameras = {n: Camera(CameraConfig(width=n, height=n)) for n in (*SIZES, REFERENCE_SIZE)}
    seconds = dict.fromkeys(SIZES, 0.0)
    errors: dict[int, list[float]] = {n: [] for n in SIZES}
    for state in navigator_states(env, steps, seed):
        reference = cameras[REFERENCE_SIZE].render(u.sim, state)["depth"]
        for n in SIZES:
            t0 = time.perf_counter()
            depth = cameras[n].render(u.sim, state)["depth"]
            seconds[n] += time.perf_counter() - t0
            errors[n].append(float(np.abs(resample(depth, REFERENCE_SIZE) - reference).mean()))
    env.close()
    return [{"size": n, "frame_us": 1e6 * seconds[n] / steps, "mean_mm": 1e3 * float(np.mean(errors[n])),
             "default": n == DEFAULT_SIZE} for n in SIZES]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"{args.steps} navigator poses, TinyRenderer RGB-D; error against {REFERENCE_SIZE}x{REFERENCE_SIZE}\n")
    print(table_header("size", "frame (us)", "frames/s", "mean depth error (mm)"))
    for r in rows(args.steps, args.seed):
        print(f"| {r['size']}x{r['size']}{' (default)' if r['default'] else ''} | {r['frame_us']:.0f} | "
              f"{1e6 / r['frame_us']:,.0f} | {r['mean_mm']:.1f} |")


if __name__ == "__main__":
    main()
