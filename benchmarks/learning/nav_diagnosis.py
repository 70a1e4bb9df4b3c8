"""Why a ClutterNav-v1 policy fails where the scripted potential field succeeds: episode traces, the observation
normalisation's view of each density, and the training curves.

For each density, the run's policy and the potential field drive the same held-out layouts (episode ``i`` reset
with seed ``EVAL_SEED + i``). Every failed episode of the policy is classed by what the trace shows:

* ``collision``: it touched an obstacle;
* ``stalled``: a timeout with the base within ``STALL_RADIUS`` m of one point over the last ``STALL_STEPS`` steps
  (stopped, or turning on the spot);
* ``orbiting``: a timeout that came within 1 m of the goal and did not reach it;
* ``wandering``: any other timeout.

The per-density lines also give what the policy commands (mean forward command), how often the collision monitor
held it back (``safety_scale < 1``) or spun it (``safety_recovery``), and the path efficiency of its successes
(start-to-goal path distance / distance driven). The normalisation section prints, per observation entry, the
running mean and std the policy sees its inputs through and the share of inputs more than 3 std from the mean at
each density. The curves section prints PPO's logged scalars (entropy, std, value loss, explained variance,
validations) from the run's TensorBoard file.

    python -m benchmarks.learning.nav_diagnosis --run out/mapless [--episodes 30] [--densities 0.05 0.12 0.2]
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.learning.run_curves import scalars
from clutter_gym.training import load
from clutter_gym.training.baselines import PotentialFieldNavigator
from clutter_gym.training.config import EVAL_SEED

STALL_STEPS, STALL_RADIUS = 100, 0.3
CURVE_TAGS = ("train/entropy_loss", "train/std", "train/value_loss", "train/explained_variance",
              "train/approx_kl", "rollout/ep_rew_mean", "rollout/ep_len_mean", "validation/success_rate")


def trace(env: gym.Env, policy, seed: int) -> dict:
    """One episode: positions, the policy's commands, the monitor's interventions, the raw observations."""
    obs, _ = env.reset(seed=seed)
    base = env.unwrapped
    start = base.robot_state().position[:2].copy()
    path0 = base.task.path_distance(base.robot_state())
    state, xy, actions, scales, spins, observations = None, [start], [], [], [], [obs]
    goal = np.asarray(base.scene.goal, dtype=float)
    success = collided = False
    while True:
        action, state = policy(obs, state)
        obs, _, terminated, truncated, info = env.step(action)
        xy.append(base.robot_state().position[:2].copy())
        actions.append(np.asarray(action, dtype=float))
        scales.append(float(info.get("safety_scale", 1.0)))
        spins.append(bool(info.get("safety_recovery", False)))
        observations.append(obs)
        collided |= info["cost"] > 0
        if terminated or truncated:
            success = bool(info["is_success"])
            break
    xy = np.array(xy)
    return {"success": success, "collision": collided, "xy": xy, "actions": np.array(actions),
            "scales": np.array(scales), "spins": np.array(spins), "observations": observations,
            "goal_distance": np.hypot(*(xy - goal).T), "path0": path0,
            "driven": float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))}


def failure_kind(t: dict) -> str:
    if t["success"]:
        return "success"
    if t["collision"]:
        return "collision"
    tail = t["xy"][-STALL_STEPS:]
    if np.max(np.hypot(*(tail - tail.mean(axis=0)).T)) < STALL_RADIUS:
        return "stalled"
    if t["goal_distance"].min() < 1.0:
        return "orbiting"
    return "wandering"


def summary(name: str, traces: list[dict]) -> str:
    kinds = Counter(failure_kind(t) for t in traces)
    actions = np.concatenate([t["actions"] for t in traces])
    scales = np.concatenate([t["scales"] for t in traces])
    spins = np.concatenate([t["spins"] for t in traces])
    wins = [t for t in traces if t["success"]]
    efficiency = np.mean([t["path0"] / max(t["driven"], 1e-6) for t in wins]) if wins else float("nan")
    length = np.mean([len(t["actions"]) for t in wins]) if wins else float("nan")
    return (f"  {name:<16} " + " ".join(f"{k} {kinds.get(k, 0):>2}" for k in
                                        ("success", "collision", "stalled", "orbiting", "wandering"))
            + f" | forward cmd {actions[:, 0].mean():+.2f} (|turn| {np.abs(actions[:, 1]).mean():.2f})"
            + f" | monitor held {np.mean(scales < 1):.0%}, spun {np.mean(spins):.0%}"
            + f" | successes: {length:.0f} steps, path efficiency {efficiency:.2f}")


def normalisation(agent, by_density: dict[float, list[dict]]) -> list[str]:
    rms = agent._normalizer.obs_rms if agent._normalizer is not None else None
    if rms is None:
        return ["  (the run does not normalise observations)"]
    lines = []
    for key, stats in rms.items():
        std = np.sqrt(stats.var + agent._normalizer.epsilon)
        lines.append(f"  {key:<9} mean {_span(stats.mean)}  std {_span(std)}")
        for density, traces in by_density.items():
            raw = np.array([np.asarray(o[key], dtype=float).ravel() for t in traces for o in t["observations"]])
            z = (raw - stats.mean.ravel()) / std.ravel()
            clipped = np.mean(np.abs(z) > agent._normalizer.clip_obs)
            lines.append(f"    density {density:<5} raw {_span(raw.mean(axis=0))}; "
                         f"|z| > 3: {np.mean(np.abs(z) > 3):.1%}, clipped at {agent._normalizer.clip_obs:g}: "
                         f"{clipped:.1%}, mean |z| {np.abs(z).mean():.2f}")
    return lines


def _span(values: np.ndarray) -> str:
    values = np.asarray(values, dtype=float).ravel()
    if values.size <= 3:
        return "[" + ", ".join(f"{v:.3g}" for v in values) + "]"
    return f"{values.min():.3g}..{values.max():.3g} (median {np.median(values):.3g})"


def curves(run: Path) -> list[str]:
    lines = []
    for tag in CURVE_TAGS:
        steps, values = scalars(run, tag)
        if len(steps):
            picks = list(range(0, len(steps), max(1, len(steps) // 8))) + [len(steps) - 1]
            lines.append(f"  {tag:<26} " + "  ".join(f"{steps[k] // 1000}k:{values[k]:.3g}" for k in picks))
    return lines or ["  (no TensorBoard scalars)"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", required=True, help="a ClutterNav-v1 run folder")
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--densities", type=float, nargs="+", default=[0.05, 0.12, 0.2])
    args = parser.parse_args()
    agent = load(args.run)
    by_density = {}
    for density in args.densities:
        env = agent.make_env(obstacle_density=density)
        field = PotentialFieldNavigator.for_env(env)
        try:
            ours = [trace(env, agent.predict, EVAL_SEED + i) for i in range(args.episodes)]
            scripted = [trace(env, lambda o, s: (field(o), s), EVAL_SEED + i) for i in range(args.episodes)]
        finally:
            env.close()
        by_density[density] = ours
        print(f"density {density}, {args.episodes} held-out layouts:")
        print(summary("policy", ours))
        print(summary("potential field", scripted))
        both = [i for i, (a, b) in enumerate(zip(ours, scripted)) if b["success"] and not a["success"]]
        print(f"  the field succeeds where the policy fails: {len(both)} layouts "
              f"({', '.join(failure_kind(ours[i]) for i in both)})")
    print("observation normalisation (the policy's running statistics; inputs at each density):")
    print("\n".join(normalisation(agent, by_density)))
    print("training curves:")
    print("\n".join(curves(Path(args.run))))


if __name__ == "__main__":
    main()
