"""ClutterReach-v1's reduced dynamics against full physics, side by side in one process: the end effector's divergence
over seeded drives in empty space, the proximity field's and the planner reference's closed-loop episodes on held-out
layouts with the step time each model costs, and both models' steps/s beside panda-gym's PandaReach-v3 (if installed)
in alternating blocks.

    python -m benchmarks.dynamics.arm_error [--drives 20] [--episodes 100] [--rounds 6]

Prints the tables of docs/speed-vs-error.md, "Reduced dynamics (ClutterReach-v1)".
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.dynamics.episodes import closed_loop as episodes_closed_loop
from benchmarks.dynamics.episodes import loop_cells, print_versus_panda
from benchmarks.learning.baselines import REACH_SENSORS
from clutter_gym.dynamics.arm_check import compare_drives
from clutter_gym.training.baselines import ProximityFieldReacher
from clutter_gym.training.joint_planner import JointPlannerReacher

#: seconds after which a drive's divergence is read; s each random command is held
MARKS, HOLD = (1.0, 5.0, 20.0), 0.25
#: the closed-loop controllers: name -> (gym.make arguments, policy factory from the env)
CONTROLLERS: dict[str, tuple[dict[str, Any], Callable[[gym.Env], Any]]] = {
    "proximity field": ({"observe_directions": True},
                        lambda env: ProximityFieldReacher.for_env(env, attraction=REACH_SENSORS.residual_gain)),
    "planner reference": ({}, JointPlannerReacher),
}


def divergence(drives: int) -> dict[float, np.ndarray]:
    """End-effector gaps (m) between pybullet and the model after each of :data:`MARKS`, one per seeded drive of
    random joint commands (within 0.7 of full scale, each held :data:`HOLD` s) from the ready pose."""
    env = gym.make("ClutterReach-v1")
    arm = env.unwrapped.robot
    env.close()
    gaps: dict[float, list[float]] = {mark: [] for mark in MARKS}
    for seed in range(drives):
        commands = np.random.default_rng(seed).uniform(-0.7, 0.7, (int(max(MARKS) / HOLD), 7))
        full, reduced = compare_drives(arm.model, arm.config, 240.0, 10, 20.0, commands, HOLD)
        for mark in MARKS:
            i = int(mark * 20.0) - 1
            gaps[mark].append(float(np.linalg.norm(full[i] - reduced[i])))
    return {mark: np.array(g) for mark, g in gaps.items()}


def closed_loop(controller: str, mode: str, episodes: int) -> dict[str, float]:
    """A controller's episodes under ``mode``: success, collision episodes, the env's step time (ms) and the share of
    steps the reduced model ran."""
    kwargs, make = CONTROLLERS[controller]
    env = gym.make("ClutterReach-v1", dynamics=mode, **kwargs)
    return episodes_closed_loop(env, make(env), episodes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drives", type=int, default=20)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--rounds", type=int, default=6)
    args = parser.parse_args()
    print(f"## End-effector divergence of {args.drives} seeded drives in empty space (commands held {HOLD} s)\n")
    print("| after | gap median / 90th pct / max (m) |")
    print("|---|---|")
    for mark, gaps in divergence(args.drives).items():
        print(f"| {mark:g} s | {np.median(gaps):.4f} / {np.percentile(gaps, 90):.4f} / {gaps.max():.4f} |")
    print(f"\n## Closed loop, {args.episodes} held-out layouts (6 obstacles and the shelf)\n")
    print("| controller | dynamics | success | collision episodes | reduced steps | env step (ms) | speed-up |")
    print("|---|---|---|---|---|---|---|")
    for controller in CONTROLLERS:
        rows = {mode: closed_loop(controller, mode, args.episodes) for mode in ("physics", "reduced")}
        for mode, row in rows.items():
            print(f"| {controller} | {mode} | {loop_cells(row, rows['physics']['ms'])}")
    print_versus_panda("ClutterReach-v1", args.rounds)


if __name__ == "__main__":
    main()
