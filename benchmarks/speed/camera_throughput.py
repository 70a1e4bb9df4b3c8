"""ClutterNav-v1 with an 84x84 RGB-D camera against gym-pybullet-drones' 64x48-camera env, side by side.

The peer is rebuilt call for call in ``benchmarks.peers.drones`` (the package cannot be installed here). Both
run in alternating blocks of uniform-random actions in one process; each block counts the time in ``step`` and in
the resets that episode ends trigger, as a training loop pays them. Figures are medians over blocks. Variants of
ours show what the camera costs (no camera, 64x48) and what the nominal noise profile adds on top.

    python -m benchmarks.speed.camera_throughput
"""

from __future__ import annotations

import argparse
import statistics

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import run_block, table_header
from benchmarks.peers.drones import make_drone_camera_workload

CAMERA = {"sensors": ("lidar", "imu", "camera"), "camera_modes": ("rgb", "depth")}
VARIANTS = {
    "ClutterNav-v1, LIDAR + IMU, no camera": {},
    "ClutterNav-v1 + camera 64x48 RGB-D": {**CAMERA, "camera_size": (64, 48)},
    "ClutterNav-v1 + camera 84x84 RGB-D": {**CAMERA, "camera_size": (84, 84)},
    "ClutterNav-v1 + camera 84x84 RGB-D, nominal noise": {**CAMERA, "camera_size": (84, 84), "noise": "nominal"},
}
PEER = "gym-pybullet-drones HoverAviary, 64x48 RGB camera (reconstructed)"


def block(env, actions: np.ndarray) -> tuple[float, float]:
    """(steps/s counting resets, steps/s in step() only) over one block of actions."""
    step_s, reset_s = run_block(env, actions)
    return len(actions) / (step_s + reset_s), len(actions) / step_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    envs = {label: gym.make("ClutterNav-v1", **kwargs) for label, kwargs in VARIANTS.items()}
    for env in envs.values():
        env.reset(seed=args.seed)
    peer = make_drone_camera_workload()
    peer.reset()
    rng = np.random.default_rng(args.seed)
    rows: dict[str, list[tuple[float, float]]] = {label: [] for label in [*envs, PEER]}
    for _ in range(args.rounds):
        nav_actions = rng.uniform(-1, 1, (args.steps, 2)).astype(np.float32)
        for label, env in envs.items():
            rows[label].append(block(env, nav_actions))
        rows[PEER].append(block(peer, rng.uniform(-1, 1, (args.steps, 1, 4)).astype(np.float32)))
    peer_rate = statistics.median(r[0] for r in rows[PEER])
    print(f"{args.rounds} alternating blocks of {args.steps} uniform-random steps; medians over blocks\n")
    print(table_header("env", "steps/s (resets included)", "steps/s (step only)", "vs peer"))
    for label, values in rows.items():
        total, step_only = statistics.median(v[0] for v in values), statistics.median(v[1] for v in values)
        print(f"| {label} | {total:,.0f} | {step_only:,.0f} | {total / peer_rate:.2f}x |")
    for env in envs.values():
        env.close()
    peer.close()


if __name__ == "__main__":
    main()
