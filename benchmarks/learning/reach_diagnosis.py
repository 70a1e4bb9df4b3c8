"""Where a ClutterReach agent fails: its held-out episodes split by where the target is (in the shelf, or above the
table) and by how they end (success, a contact, the time limit).

    python -m benchmarks.learning.reach_diagnosis --run runs/ClutterReach-v1/none-seed0 --episodes 100
    python -m benchmarks.learning.reach_diagnosis --over-and-down

``--over-and-down`` drives the student's interface with no policy instead of a run: the hand controller taking
the hand over the target and down onto it (it reads only the target), in the env of the shipped ``sensors`` block.

Episode i is reset with seed 1,000,000 + i, the layouts of the baseline tables. A target is in the shelf when it
lies within 0.2 m (the shelf's half width) of the shelf's centre in the table's plane; the shelf is the layout's
first five obstacles (clutter_gym.worlds.table.sample).
"""

from __future__ import annotations

import argparse
import math
from collections import Counter
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from clutter_gym.training import load
from clutter_gym.training.config import EVAL_SEED, config_for, read_hyperparams_file, user_settings
from clutter_gym.training.line_up_teachers import over_route, route_action
from clutter_gym.training.residual import SubgoalResidual

SHELF_PARTS = 5
SHELF_HALF_WIDTH = 0.2


def where(scene) -> str:
    """"shelf" or "table": where the layout's target lies."""
    centre = np.mean([np.asarray(o.position)[:2] for o in scene.obstacles[:SHELF_PARTS]], axis=0)
    return "shelf" if np.linalg.norm(np.asarray(scene.target[:2]) - centre) < SHELF_HALF_WIDTH else "table"


def _agent(run: str) -> tuple[gym.Env, Callable]:
    agent = load(run)
    return agent.make_env(), agent.predict


def over_and_down() -> tuple[gym.Env, Callable]:
    """The sensors block's env behind the hand controller, and a policy taking the hand over the target (at the
    line-up teacher's travel height) and down onto it, pointing down."""
    config = config_for("ClutterReach-v1", user_settings(read_hyperparams_file("sensors"), "ClutterReach-v1"))
    env = SubgoalResidual(gym.make("ClutterReach-v1", **config.make_kwargs()), 0.0, space="waypoint")
    hand = env.pursuit.hand

    def predict(obs: dict, state: Any) -> tuple[np.ndarray, Any]:
        here = hand.frames(np.asarray(obs["joint_position"], dtype=float))[0, :3, 3]
        return route_action(here, over_route(np.asarray(obs["target"], dtype=float)), math.pi / 2), state
    return env, predict


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", help="a ClutterReach run folder, or pretrained/NAME")
    parser.add_argument("--over-and-down", action="store_true", help="the hand controller alone, no policy")
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    if (args.run is None) == (not args.over_and_down):
        parser.error("give --run RUN or --over-and-down")
    env, predict = over_and_down() if args.over_and_down else _agent(args.run)
    tally: Counter = Counter()
    try:
        for i in range(args.episodes):
            obs, info = env.reset(seed=EVAL_SEED + i)
            place, state, done, touched = where(env.unwrapped.scene), None, False, False
            while not done:
                action, state = predict(obs, state)
                obs, _, terminated, truncated, info = env.step(action)
                touched |= info["n_contacts"] > 0
                done = terminated or truncated
            tally[place, "success" if info["is_success"] else "contact" if touched else "time limit"] += 1
    finally:
        env.close()
    print("| target | episodes | success | contact | time limit |\n|---|---|---|---|---|")
    for place in ("table", "shelf"):
        counts = [tally[place, end] for end in ("success", "contact", "time limit")]
        print(f"| {place} | {sum(counts)} | " + " | ".join(str(c) for c in counts) + " |")


if __name__ == "__main__":
    main()
