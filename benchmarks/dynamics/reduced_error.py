"""ClutterNav-v1's reduced dynamics against full physics, side by side in one process: the divergence of seeded open-
floor drives, the potential field's closed-loop episodes on held-out layouts with the step time each model costs,
and both models' steps/s beside panda-gym's PandaReach-v3 (if installed) in alternating blocks.

    python -m benchmarks.dynamics.reduced_error [--drives 20] [--episodes 100] [--density 0.12] [--rounds 6]

Prints the tables of docs/speed-vs-error.md, "Reduced dynamics".
"""

from __future__ import annotations

import argparse
import math

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.dynamics.episodes import closed_loop as episodes_closed_loop
from benchmarks.dynamics.episodes import loop_cells, print_versus_panda
from clutter_gym.training.baselines import PotentialFieldNavigator

#: seconds after which a drive's divergence is read; s each random command is held
MARKS, HOLD = (1.0, 5.0, 20.0), 0.5
#: the open floor: a 30 m arena without clutter, the base at its centre, the goal in a far corner
OPEN = {"arena_size": 30.0, "obstacle_density": 0.0}
CENTRE = {"scene": {"start": [0.0, 0.0, 0.0], "goal": [13.0, 13.0], "obstacles": []}}


def drive(env: gym.Env, commands: np.ndarray) -> np.ndarray:
    """(x, y, yaw) of the base after each step of ``commands`` from the open floor's centre."""
    env.reset(seed=0, options=CENTRE)
    base = env.unwrapped
    poses = np.empty((len(commands), 3))
    for i, command in enumerate(commands):
        base.step(command)
        state = base.dynamics.state()
        poses[i] = state.position[0], state.position[1], state.yaw
    return poses


def divergence(drives: int) -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """Position (m) and heading (rad) gaps between the models after each of :data:`MARKS`, one per seeded drive."""
    envs = {mode: gym.make("ClutterNav-v1", dynamics=mode, **OPEN) for mode in ("physics", "reduced")}
    control_hz = envs["physics"].unwrapped.control_hz
    steps, hold = int(max(MARKS) * control_hz), int(HOLD * control_hz)
    gaps = {mark: ([], []) for mark in MARKS}
    for seed in range(drives):
        commands = np.repeat(np.random.default_rng(seed).uniform(-1, 1, (steps // hold, 2)), hold, axis=0)
        full, reduced = (drive(envs[mode], commands.astype(np.float32)) for mode in ("physics", "reduced"))
        for mark in MARKS:
            i = int(mark * control_hz) - 1
            gaps[mark][0].append(math.dist(full[i, :2], reduced[i, :2]))
            gaps[mark][1].append(abs(math.remainder(full[i, 2] - reduced[i, 2], 2 * math.pi)))
    for env in envs.values():
        env.close()
    return {mark: (np.array(p), np.array(h)) for mark, (p, h) in gaps.items()}


def closed_loop(mode: str, episodes: int, density: float, handover: str = "step") -> dict[str, float]:
    """The potential field's episodes under ``mode``: success, collision episodes, the env's step time (ms) and the
    share of steps the reduced model ran."""
    env = gym.make("ClutterNav-v1", dynamics=mode, obstacle_density=density)
    if handover != "step":
        env.unwrapped.dynamics.handover = handover
    return episodes_closed_loop(env, PotentialFieldNavigator.for_env(env), episodes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drives", type=int, default=20)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--density", type=float, default=0.12)
    parser.add_argument("--rounds", type=int, default=6)
    args = parser.parse_args()
    print(f"## Divergence of {args.drives} seeded open-floor drives (random commands held {HOLD} s)\n")
    print("| after | position gap median / 90th pct / max (m) | heading gap median / 90th pct / max (deg) |")
    print("|---|---|---|")
    for mark, (position, heading) in divergence(args.drives).items():
        h = np.degrees(heading)
        print(f"| {mark:g} s | {np.median(position):.3f} / {np.percentile(position, 90):.3f} / {position.max():.3f} "
              f"| {np.median(h):.1f} / {np.percentile(h, 90):.1f} / {h.max():.1f} |")
    print(f"\n## Potential field, {args.episodes} held-out layouts at density {args.density}\n")
    print("| dynamics | success | collision episodes | reduced steps | env step (ms) | speed-up |")
    print("|---|---|---|---|---|---|")
    rows = {name: closed_loop(mode, args.episodes, args.density, handover) for name, mode, handover in
            (("physics", "physics", "step"), ("reduced, hand-over per step", "reduced", "step"),
             ("reduced, hand-over for the episode", "reduced", "episode"))}
    for name, row in rows.items():
        print(f"| {name} | {loop_cells(row, rows['physics']['ms'])}")
    print_versus_panda("ClutterNav-v1", args.rounds)


if __name__ == "__main__":
    main()
