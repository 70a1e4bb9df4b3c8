"""Why ClutterFly's flyer breaks under ``harsh``, and what holds it: the map-based planner reference (the cascaded
flyer on the subgoal) with and without its thrust estimate and with its attitude gain as shipped or lowered, under
each part of ``harsh`` on its own and all of it.

The parts: the command's two-step delay, Gaussian noise on the command, and the per-episode dynamics (mass and motor
strength within +-20 %, friction, restitution). Each cell flies the same held-out layouts (episode ``i`` reset with
seed ``EVAL_SEED + i``) and reports success / collision episodes with 95% Wilson intervals. Writes the table to
``OUT/fly_harsh.md`` and, to ``OUT/fly_harsh.json``, what each column flew under, each row's settings and every
episode of every cell.

    python -m benchmarks.learning.fly_harsh [--episodes 100] [--out out/fly_harsh] [--workers 2] [--columns NAME ...]
"""

from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict
from pathlib import Path
from typing import Any

import gymnasium as gym

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.learning.baselines import cell_text
from clutter_gym.noise.profiles import resolve_noise
from clutter_gym.training.baselines import CascadedFlyer
from clutter_gym.training.config import EVAL_SEED, config_for
from clutter_gym.training.evaluate import rollouts
from clutter_gym.util.atomic import write_text_atomically

FLY = config_for("ClutterFly-v1")
#: Column name and the noise it flies under: each part of ``harsh`` alone on the clean profile, then all of it.
_HARSH = resolve_noise("harsh")
COLUMNS: dict[str, Any] = {
    "none": "none",
    "command delay (2 steps)": {"profile": "none", "action": {"latency_steps": _HARSH.action.latency_steps}},
    "command noise": {"profile": "none", "action": {"sigma": _HARSH.action.sigma}},
    "dynamics": {"profile": "none", "dynamics": asdict(_HARSH.dynamics)},
    "harsh": "harsh",
}
#: Row name, whether the flyer reads the env's ``thrust_ratio``, and its attitude gain (1/s).
ROWS = [
    ("flyer as shipped (datasheet hover thrust, attitude gain 6)", False, 6.0),
    ("+ thrust estimate", True, 6.0),
    ("+ attitude gain 4", False, 4.0),
    ("+ both (the robust residual's base)", True, 4.0),
]


def cell(reads_ratio: bool, attitude_gain: float, noise: Any, episodes: int) -> list[dict[str, float]]:
    env = gym.make("ClutterFly-v1", noise=noise, subgoal_lookahead=FLY.env_kwargs["subgoal_lookahead"],
                   observe_thrust_ratio=reads_ratio)
    try:
        flyer = CascadedFlyer.for_env(env, "subgoal", position_gain=FLY.residual_gain, attitude_gain=attitude_gain)
        return rollouts(env, lambda obs, state: (flyer(obs), None), episodes, EVAL_SEED)
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--out", default="out/fly_harsh")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="processes running cells")
    parser.add_argument("--columns", nargs="+", choices=list(COLUMNS), default=list(COLUMNS), metavar="NAME",
                        help="fly only these columns, of: " + ", ".join(f'"{c}"' for c in COLUMNS))
    args = parser.parse_args()
    columns = {column: noise for column, noise in COLUMNS.items() if column in args.columns}
    lines = ["| flyer on the subgoal | " + " | ".join(f"`{c}`" for c in columns) + " |",
             "|---|" + "---|" * len(columns)]
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {(name, column): pool.submit(cell, reads_ratio, gain, noise, args.episodes)
                   for name, reads_ratio, gain in ROWS for column, noise in columns.items()}
        results = {name: {column: futures[name, column].result() for column in columns} for name, _, _ in ROWS}
    for name, _, _ in ROWS:
        lines.append(f"| {name} | " + " | ".join(cell_text(rows) for rows in results[name].values()) + " |")
    lines.append(f"\nClutterFly-v1 at its default density. Success / collision episodes, {args.episodes} episodes per "
                 f"cell (seeds {EVAL_SEED}..), 95% Wilson intervals.")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomically(out / "fly_harsh.md", "\n".join(lines) + "\n")
    settings = {name: {"thrust_estimate": reads_ratio, "attitude_gain": gain} for name, reads_ratio, gain in ROWS}
    write_text_atomically(out / "fly_harsh.json",
                          json.dumps({"columns": columns, "rows": settings, "cells": results}, indent=1))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
