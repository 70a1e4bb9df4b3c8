"""ClutterFly-v1's reduced dynamics against full physics, side by side in one process: the divergence of seeded
free flights, the planner reference's closed-loop episodes on held-out layouts with the step time each model costs,
and both models' steps per CPU-second with resets beside the rebuilt HoverAviary KIN peer in alternating blocks.

    python -m benchmarks.dynamics.flight_error [--flights 20] [--episodes 100] [--density 0.05] [--rounds 6]

Prints the tables of docs/speed-vs-error.md, "Reduced dynamics (ClutterFly-v1)".
"""

from __future__ import annotations

import argparse
import statistics

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.dynamics.episodes import closed_loop as episodes_closed_loop
from benchmarks.dynamics.episodes import loop_cells
from benchmarks.harness import alternating_rounds
from benchmarks.peers.hover import HoverKinPeer
from benchmarks.speed.fly_throughput import run_block
from clutter_gym.dynamics.flight_check import compare_flights
from clutter_gym.training.baselines import CascadedFlyer
from clutter_gym.training.config import config_for

#: seconds after which a flight's divergence is read; s each random command is held
MARKS, HOLD = (1.0, 5.0, 20.0), 0.25
#: the planner reference of docs/baselines.md: the flyer on the subgoal, with the shipped block's gain
FLY = config_for("ClutterFly-v1")


def divergence(flights: int, control: str = "rates") -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """Position (m) and attitude (rad) gaps between pybullet and the model after each of :data:`MARKS`, one per seeded
    free flight of random commands (within +-0.5 of the hover action, each held :data:`HOLD` s)."""
    env = gym.make("ClutterFly-v1")
    robot = env.unwrapped.robot
    model, config = robot.model, type(robot.config)(control=control)
    env.close()
    gaps: dict[float, tuple[list[float], list[float]]] = {mark: ([], []) for mark in MARKS}
    for seed in range(flights):
        offsets = np.random.default_rng(seed).uniform(-0.5, 0.5, (int(max(MARKS) / HOLD), 4))
        full, reduced = compare_flights(model, config, 240.0, 10, 30.0, offsets, HOLD, height=1000.0)
        for mark in MARKS:
            i = int(mark * 30.0) - 1
            gaps[mark][0].append(float(np.linalg.norm(full[i, :3] - reduced[i, :3])))
            gaps[mark][1].append(attitude_gap(full[i, 3:], reduced[i, 3:]))
    return {mark: (np.array(p), np.array(a)) for mark, (p, a) in gaps.items()}


def attitude_gap(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (rad) between the attitudes of unit quaternions ``a`` and ``b`` (q and -q are one attitude),
    4 atan2(|a - b|, |a + b|) with ``b``'s sign matched: exact near zero, where arccos of the dot product is not."""
    b = b if float(a @ b) >= 0.0 else -b
    return 4.0 * float(np.arctan2(np.linalg.norm(a - b), np.linalg.norm(a + b)))


def closed_loop(mode: str, episodes: int, density: float) -> dict[str, float]:
    """The planner reference's episodes under ``mode``: success, collision episodes, the env's step time (ms) and the
    share of steps the reduced model ran."""
    env = gym.make("ClutterFly-v1", dynamics=mode, obstacle_density=density,
                   subgoal_lookahead=FLY.env_kwargs["subgoal_lookahead"])
    return episodes_closed_loop(env, CascadedFlyer.for_env(env, "subgoal", position_gain=FLY.residual_gain), episodes)


def versus_peer(rounds: int, steps: int = 400) -> dict[str, float]:
    """Median steps per CPU-second with resets over ``rounds`` alternating blocks of ``steps`` uniform-random actions
    (as ``benchmarks.speed.fly_throughput`` runs them) of ClutterFly-v1 (IMU only) under each model and of the
    HoverAviary KIN peer, and the reduced model's share of the ClutterFly steps."""
    envs = {f"ClutterFly-v1, {mode}": gym.make("ClutterFly-v1", dynamics=mode) for mode in ("physics", "reduced")}
    peer = HoverKinPeer()
    for env in envs.values():
        env.reset(seed=0)
    peer.reset()
    rngs = {name: np.random.default_rng(0) for name in (*envs, "peer")}
    measures = {name: (lambda name=name, env=env: run_block(env, rngs[name].uniform(-1, 1, (steps, 4))))
                for name, env in envs.items()}
    measures["peer: HoverAviary KIN (rebuilt)"] = lambda: run_block(peer, rngs["peer"].uniform(-1, 1, (steps, 1, 4)))
    blocks = alternating_rounds(measures, rounds)
    rates = {name: statistics.median(b.cpu_rate for b in values) for name, values in blocks.items()}
    dynamics = envs["ClutterFly-v1, reduced"].unwrapped.dynamics
    rates["reduced share"] = dynamics.reduced_steps / max(1, dynamics.reduced_steps + dynamics.full_steps)
    return rates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", type=int, default=20)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--density", type=float, default=0.05)
    parser.add_argument("--rounds", type=int, default=6)
    args = parser.parse_args()
    for control in ("rates", "motors"):
        print(f"## Divergence of {args.flights} seeded free flights ({control} commands held {HOLD} s)\n")
        print("| after | position gap median / max (m) | attitude gap median / max (rad) |")
        print("|---|---|---|")
        for mark, (position, attitude) in divergence(args.flights, control).items():
            print(f"| {mark:g} s | {np.median(position):.1e} / {position.max():.1e} "
                  f"| {np.median(attitude):.1e} / {attitude.max():.1e} |")
        print()
    print(f"## Planner reference, {args.episodes} held-out layouts at density {args.density}\n")
    print("| dynamics | success | collision episodes | reduced steps | env step (ms) | speed-up |")
    print("|---|---|---|---|---|---|")
    rows = {mode: closed_loop(mode, args.episodes, args.density) for mode in ("physics", "reduced")}
    for mode, row in rows.items():
        print(f"| {mode} | {loop_cells(row, rows['physics']['ms'])}")
    rates = versus_peer(args.rounds)
    share = rates.pop("reduced share")
    peer = rates["peer: HoverAviary KIN (rebuilt)"]
    print(f"\n## Random actions with resets, {args.rounds} alternating blocks (median steps per CPU-s)\n")
    for name, rate in rates.items():
        print(f"- {name}: {rate:,.0f}" + (f", {rate / peer:.2f}x the peer" if not name.startswith("peer") else ""))
    print(f"- the reduced model ran {share:.0%} of the reduced env's steps")


if __name__ == "__main__":
    main()
