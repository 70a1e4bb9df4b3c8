"""Speed against error of the LIDAR's ray count: scan time against how far the nearest return is off.

The scripted navigator drives ClutterNav-v1 through seeded layouts; at every pose each ray count casts its scan
(interleaved, so machine noise hits them alike) and so does a 4,096-ray reference. The error is what a sparse
scan misses: its nearest return less the reference's (never negative, as the reference's beams include its
own), which is how much closer the nearest obstacle is than the scan says. Ranges are clean (no noise profile).

    python -m benchmarks.fidelity.lidar_resolution
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import navigator_states, table_header
from clutter_gym.sensors.lidar import Lidar, LidarConfig

RAY_COUNTS = (16, 32, 64, 128, 256, 512)
REFERENCE_RAYS = 4096
DEFAULT_RAYS = LidarConfig.n_rays


def rows(steps: int = 600, seed: int = 0) -> list[dict]:
    """Per ray count: scan time (us), mean and p95 nearest-return error (mm), and whether it is the default."""
    env = gym.make("ClutterNav-v1")
    u = env.unwrapped
    scanners = {n: Lidar(LidarConfig(n_rays=n)) for n in (*RAY_COUNTS, REFERENCE_RAYS)}
    seconds = dict.fromkeys(RAY_COUNTS, 0.0)
    errors: dict[int, list[float]] = {n: [] for n in RAY_COUNTS}
    for state in navigator_states(env, steps, seed):
        nearest = float(scanners[REFERENCE_RAYS].read_clean(u.sim, state).min())
        for n in RAY_COUNTS:
            t0 = time.perf_counter()
            ranges = scanners[n].read_clean(u.sim, state)
            seconds[n] += time.perf_counter() - t0
            errors[n].append(float(ranges.min()) - nearest)
    env.close()
    return [{"rays": n, "scan_us": 1e6 * seconds[n] / steps, "mean_mm": 1e3 * float(np.mean(errors[n])),
             "p95_mm": 1e3 * float(np.percentile(errors[n], 95)), "default": n == DEFAULT_RAYS}
            for n in RAY_COUNTS]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"{args.steps} navigator poses; error = nearest return less the {REFERENCE_RAYS}-ray scan's\n")
    print(table_header("rays", "scan (us)", "mean error (mm)", "p95 error (mm)"))
    for r in rows(args.steps, args.seed):
        print(f"| {r['rays']}{' (default)' if r['default'] else ''} | {r['scan_us']:.0f} | {r['mean_mm']:.1f} | "
              f"{r['p95_mm']:.1f} |")


if __name__ == "__main__":
    main()
