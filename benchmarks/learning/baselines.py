"""Baseline tables for ClutterNav-v1, ClutterReach-v1 and ClutterFly-v1: scripted and learned policies, success
and collision rates with 95% intervals at three clutter levels and several noise profiles, on the same held-out
layouts for every row.

ClutterNav-v1 rows: the mapless potential field; the map-based planner reference (the same field steering for the
``subgoal`` waypoint of the costmap planner, an upper bound of what the map allows a simple controller).
ClutterReach-v1 rows: scripted IK, the end effector heading straight for the target (``control="ee_position"``);
the proximity field (sensor-only: the target, the arm's joint positions and each link's proximity reading; the
sensor-only PPO residual's base); the joint-space planner reference (RRT-Connect on the known layout, then path
tracking in joint velocities); the pursuit of the ``subgoal`` on that path that the shipped PPO residual policy
adds its actions to.
ClutterFly-v1 rows: a cascaded position controller flying straight at the goal (mapless); the same controller on
the ``subgoal`` of the shortest path through the known layout (the map-based planner reference, and the pursuit
the shipped PPO residual policy adds its actions to).
Then one row per trained run given with ``--run NAME=RUN_DIR`` (its own env settings; the clutter level and the
profile changed per cell). Episode ``i`` of every cell is reset with seed ``EVAL_SEED + i``, so rows are compared
on identical layouts.

    python -m benchmarks.learning.baselines --run "PPO subgoal=out/learning/seed0/run" [--episodes 50] \
        [--out docs/baselines]
    python -m benchmarks.learning.baselines --env ClutterReach-v1 --run "PPO=runs/ClutterReach-v1/none-seed0"
    python -m benchmarks.learning.baselines --env ClutterReach-v1 --no-scripted --run "another row=RUN_DIR"
    python -m benchmarks.learning.baselines --env ClutterFly-v1 --run "PPO residual=runs/ClutterFly-v1/none-seed0"
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import table_header
from clutter_gym.training import load
from clutter_gym.training.baselines import (
    CascadedFlyer,
    PotentialFieldNavigator,
    ProximityFieldReacher,
    StraightLineReacher,
)
from clutter_gym.training.config import EVAL_SEED, config_for, read_hyperparams_file, user_settings
from clutter_gym.training.evaluate import rollouts, summarize
from clutter_gym.training.joint_planner import JointPlannerReacher
from clutter_gym.training.residual import subgoal_pursuit
from clutter_gym.util.atomic import write_text_atomically

#: The subgoal lookahead the planner reference runs with, metres.
PLANNER_LOOKAHEAD = 0.5
#: The shipped ClutterReach settings: the subgoal pursuit row runs with their lookahead and gain.
REACH = config_for("ClutterReach-v1")
#: The last round's sensor-only ClutterReach settings (PPO): the proximity field row runs with their gain.
REACH_SENSORS = config_for("ClutterReach-v1", user_settings(read_hyperparams_file("sensors-ppo"), "ClutterReach-v1"))
#: The shipped ClutterFly settings: the planner reference runs with their lookahead.
FLY = config_for("ClutterFly-v1")
#: The shipped robust ClutterFly settings: their base (the flyer reading its thrust estimate, with their gains).
FLY_ROBUST = config_for("ClutterFly-v1", user_settings(read_hyperparams_file("robust"), "ClutterFly-v1"))

#: Per env: the gym.make argument that sets the clutter, its default levels, and the scripted rows as
#: (name, extra gym.make arguments, policy factory from the env).
TABLES: dict[str, dict[str, Any]] = {
    "ClutterNav-v1": {
        "knob": "obstacle_density", "levels": [0.05, 0.12, 0.2],
        "scripted": [
            ("potential field (mapless, scripted)", {}, PotentialFieldNavigator.for_env),
            ("planner reference (map-based: potential field on the subgoal)",
             {"subgoal_lookahead": PLANNER_LOOKAHEAD}, lambda env: PotentialFieldNavigator.for_env(env, "subgoal")),
        ],
    },
    "ClutterReach-v1": {
        "knob": "n_obstacles", "levels": [3, 6, 10],
        "scripted": [
            ("straight line (scripted IK)", {"control": "ee_position"}, StraightLineReacher.for_env),
            ("proximity field (sensor-only, scripted)", {"observe_directions": True},
             lambda env: ProximityFieldReacher.for_env(env, attraction=REACH_SENSORS.residual_gain)),
            ("planner reference (map-based: RRT-Connect in joint space)", {}, JointPlannerReacher),
            ("subgoal pursuit (map-based: the PPO residual's base alone)",
             {"subgoal_lookahead": REACH.env_kwargs["subgoal_lookahead"]},
             lambda env: subgoal_pursuit("ClutterReach-v1", REACH.residual_gain)),
        ],
    },
    "ClutterFly-v1": {
        "knob": "obstacle_density", "levels": [0.05, 0.1, 0.15],
        "scripted": [
            ("cascaded flyer on the goal (mapless, scripted)", {}, CascadedFlyer.for_env),
            ("planner reference (map-based: the flyer on the subgoal; the PPO residual's base)",
             {"subgoal_lookahead": FLY.env_kwargs["subgoal_lookahead"]},
             lambda env: CascadedFlyer.for_env(env, "subgoal", position_gain=FLY.residual_gain)),
            ("planner reference with its thrust estimate and a margin for delay (the robust residual's base)",
             {key: FLY_ROBUST.env_kwargs[key] for key in ("subgoal_lookahead", "observe_thrust_ratio")},
             lambda env: CascadedFlyer.for_env(env, "subgoal", position_gain=FLY_ROBUST.residual_gain,
                                               **FLY_ROBUST.residual_base)),
        ],
    },
}


def scripted_cell(env_id: str, extra: dict[str, Any], make_policy, clutter: dict[str, Any], profile: str,
                  episodes: int) -> list[dict[str, float]]:
    env = gym.make(env_id, noise=profile, **extra, **clutter)
    try:
        policy = make_policy(env)
        return rollouts(env, lambda obs, state: (policy(obs), None), episodes, EVAL_SEED)
    finally:
        env.close()


def agent_cell(run_dir: str, clutter: dict[str, Any], profile: str, episodes: int) -> list[dict[str, float]]:
    agent = load(run_dir)
    env = agent.make_env(noise=profile, **clutter)
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
    parser.add_argument("--env", choices=sorted(TABLES), default="ClutterNav-v1")
    parser.add_argument("--run", action="append", default=[], metavar="NAME=RUN_DIR",
                        help="a trained run to add as a row (repeatable)")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--levels", type=float, nargs="+", default=None,
                        help="clutter levels (obstacle_density for ClutterNav and ClutterFly, n_obstacles for "
                             "ClutterReach)")
    parser.add_argument("--profiles", nargs="+", default=["none", "nominal", "harsh"])
    parser.add_argument("--out", default=None, help="folder for baselines.md and .json (default out/baselines/ENV)")
    parser.add_argument("--robot", default=None, help="a registered robot (or spec file) for the scripted rows")
    parser.add_argument("--no-scripted", action="store_true",
                        help="only the --run rows (to add a row to a table: every row runs the same layouts)")
    args = parser.parse_args()
    table = TABLES[args.env]
    knob, kind = table["knob"], type(table["levels"][0])  # n_obstacles takes ints
    levels = [kind(level) for level in args.levels] if args.levels else table["levels"]
    rows: list[tuple[str, str, Any]] = [
        (name, "-", lambda c, p, extra=extra, make=make: scripted_cell(args.env, extra, make, c, p, args.episodes))
        for name, extra, make in ([] if args.no_scripted else [
            (name, {**extra, **({"robot": args.robot} if args.robot else {})}, make)
            for name, extra, make in table["scripted"]])
    ]
    for spec in args.run:
        name, _, run_dir = spec.partition("=")
        timing = load(run_dir).run.training_time()
        trained = f"{int(timing['steps']):,} steps, {timing['seconds'] / 60:.1f} min"
        rows.append((name, trained, lambda c, p, r=run_dir: agent_cell(r, c, p, args.episodes)))
    cells = [(level, p) for level in levels for p in args.profiles]
    lines = [table_header("policy", "training", *(f"{knob} {level}, `{p}`" for level, p in cells))]
    results: dict[str, dict[str, Any]] = {}
    for name, trained, run_cell in rows:
        texts, results[name] = [], {}
        for level, profile in cells:
            t0 = time.perf_counter()
            try:
                episode_rows = run_cell({knob: level}, profile)
            except ValueError as error:  # a scripted policy for another robot (--robot)
                print(f"{name}: left out ({error})", flush=True)
                results.pop(name)
                break
            results[name][f"{level}/{profile}"] = summarize(episode_rows)
            texts.append(cell_text(episode_rows))
            print(f"{name} | {knob} {level} | {profile}: {texts[-1]} ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
        if len(texts) == len(cells):
            lines.append(f"| {name} | {trained} | " + " | ".join(texts) + " |")
    robot = f" with robot {args.robot!r} (scripted rows)" if args.robot else ""
    note = (f"\n{args.env}{robot}. Success / collision episodes, {args.episodes} episodes per cell "
            f"(seeds {EVAL_SEED}..), 95% Wilson intervals in brackets. A collision episode is one with any contact.\n")
    out = Path(args.out or f"out/baselines/{args.env}")
    write_text_atomically(out / "baselines.md", "\n".join(lines) + "\n" + note)
    write_text_atomically(out / "baselines.json", json.dumps(results, indent=2))
    print("\n".join(lines) + note)


if __name__ == "__main__":
    main()
