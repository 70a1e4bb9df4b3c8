"""What noise costs: ClutterNav-v0 steps/s under each noise profile, measured side by side in one run.

Each profile runs twice: as specified (the low-cost and harsh LIDARs scan at 5-5.5 Hz, so the env casts a
quarter of the rays and gets faster), and with every sensor forced to update each control step (``rate_hz: 0``),
which isolates the cost of the noise chains, delay lines, action noise and dynamics randomisation. All envs drive
the same random-walk actions from the same seed, in alternating blocks; figures are medians over blocks.

    python benchmarks/noise_cost.py
"""

from __future__ import annotations

import argparse
import statistics

import gymnasium as gym
import numpy as np
from throughput import EnvRunner, smooth_actions

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.noise.profiles import PROFILE_NAMES

EVERY_STEP = {"lidar": {"rate_hz": 0.0}, "imu": {"rate_hz": 0.0}, "camera": {"rate_hz": 0.0}}


def configs() -> dict[str, dict]:
    out: dict[str, dict] = {}
    for name in PROFILE_NAMES:
        out[name] = {"profile": name}
        if name != "none":
            out[f"{name}, every sensor each step"] = {"profile": name, **EVERY_STEP}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=8)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    runners = {label: EnvRunner(gym.make("ClutterNav-v0", noise=spec), args.seed) for label, spec in configs().items()}
    rates: dict[str, list[float]] = {label: [] for label in runners}
    rng = np.random.default_rng(args.seed)
    for _ in range(args.rounds):
        walk = smooth_actions(rng, args.steps)
        for label, runner in runners.items():
            seconds, _, _ = runner.run(lambda obs, i, walk=walk: walk[i], args.steps)
            rates[label].append(args.steps / seconds)
    base = statistics.median(rates["none"])
    print(f"ClutterNav-v0 defaults (64-beam LIDAR + IMU), {args.rounds} alternating blocks of {args.steps} "
          "random-walk steps\n")
    print("| noise | steps/s | us/step | step time vs none |\n|---|---|---|---|")
    for label, values in rates.items():
        rate = statistics.median(values)
        print(f"| {label} | {rate:,.0f} | {1e6 / rate:.0f} | {base / rate - 1:+.1%} |")
    for runner in runners.values():
        runner.env.close()


if __name__ == "__main__":
    main()
