"""Baseline table for ClutterNav-v0: scripted and learned policies, success and collision rates with 95% intervals
at several obstacle densities and noise profiles, on the same held-out layouts for every row.

Rows: the mapless potential field; the map-based planner reference (the same field steering for the ``subgoal``
waypoint of the costmap planner, an upper bound of what the map allows a simple controller); and one row per
trained run given with ``--run NAME=RUN_DIR`` (its own env settings, densities and profiles changed per cell).
Episode ``i`` of every cell is reset with seed ``EVAL_SEED + i``, so rows are compared on identical layouts.

    python benchmarks/baselines.py --run "PPO subgoal=out/learning/seed0/run" [--episodes 50] [--out docs/baselines]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.atomic import write_text_atomically
from clutter_gym.training import load
from clutter_gym.training.baselines import PotentialFieldNavigator
from clutter_gym.training.config import EVAL_SEED
from clutter_gym.training.evaluate import rollouts, summarize

#: The subgoal lookahead the planner reference runs with, metres.
PLANNER_LOOKAHEAD = 0.5


def scripted_cell(goal_key: str, density: float, profile: str, episodes: int) -> list[dict[str, float]]:
    extra = {"subgoal_lookahead": PLANNER_LOOKAHEAD} if goal_key == "subgoal" else {}
    env = gym.make("ClutterNav-v0", noise=profile, obstacle_density=density, **extra)
    try:
        navigator = PotentialFieldNavigator.for_env(env, goal_key=goal_key)
        return rollouts(env, lambda obs, state: (navigator(obs), None), episodes, EVAL_SEED)
    finally:
        env.close()


def agent_cell(run_dir: str, density: float, profile: str, episodes: int) -> list[dict[str, float]]:
    agent = load(run_dir)
    env = agent.make_env(noise=profile, obstacle_density=density)
    try:
        return rollouts(env, agent.predict, episodes, EVAL_SEED)
    finally:
        env.close()


def cell_text(rows: list[dict[str, float]]) -> str:
    m = summarize(rows)
    s, c = m["success_rate"], m["collision_rate"]
    return (f"{s['value']:.0%} [{s['ci95'][0]:.0%}, {s['ci95'][1]:.0%}] / "
            f"{c['value']:.0%} [{c['ci95'][0]:.0%}, {c['ci95'][1]:.0%}]")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", action="append", default=[], metavar="NAME=RUN_DIR",
                        help="a trained run to add as a row (repeatable)")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--densities", type=float, nargs="+", default=[0.05, 0.12, 0.2])
    parser.add_argument("--profiles", nargs="+", default=["none", "nominal", "harsh"])
    parser.add_argument("--out", default="out/baselines")
    args = parser.parse_args()
    rows: list[tuple[str, str, Any]] = [
        ("potential field (mapless, scripted)", "-", lambda d, p: scripted_cell("goal", d, p, args.episodes)),
        ("planner reference (map-based: potential field on the subgoal)", "-",
         lambda d, p: scripted_cell("subgoal", d, p, args.episodes)),
    ]
    for spec in args.run:
        name, _, run_dir = spec.partition("=")
        timing = load(run_dir).run.training_time()
        trained = f"{int(timing['steps']):,} steps, {timing['seconds'] / 60:.1f} min"
        rows.append((name, trained, lambda d, p, r=run_dir: agent_cell(r, d, p, args.episodes)))
    cells = [(d, p) for d in args.densities for p in args.profiles]
    header = "| policy | training | " + " | ".join(f"density {d}, `{p}`" for d, p in cells) + " |"
    lines = [header, "|---|---|" + "---|" * len(cells)]
    results: dict[str, dict[str, Any]] = {}
    for name, trained, run_cell in rows:
        texts, results[name] = [], {}
        for density, profile in cells:
            t0 = time.perf_counter()
            episode_rows = run_cell(density, profile)
            results[name][f"{density}/{profile}"] = summarize(episode_rows)
            texts.append(cell_text(episode_rows))
            print(f"{name} | density {density} | {profile}: {texts[-1]} ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
        lines.append(f"| {name} | {trained} | " + " | ".join(texts) + " |")
    note = (f"\nSuccess / collision episodes, {args.episodes} episodes per cell (seeds {EVAL_SEED}..), 95% Wilson "
            "intervals in brackets. A collision episode is one with any contact.\n")
    out = Path(args.out)
    write_text_atomically(out / "baselines.md", "\n".join(lines) + "\n" + note)
    write_text_atomically(out / "baselines.json", json.dumps(results, indent=2))
    print("\n".join(lines) + note)


if __name__ == "__main__":
    main()
