"""Where a ClutterReach agent fails: its held-out episodes split by where the target is (in the shelf, or above the
table) and by how they end (success, a contact, the time limit).

    python -m benchmarks.learning.reach_diagnosis --run runs/ClutterReach-v1/none-seed0 --episodes 100

Episode i is reset with seed 1,000,000 + i, the layouts of the baseline tables. A target is in the shelf when it
lies within 0.2 m (the shelf's half width) of the shelf's centre in the table's plane; the shelf is the layout's
first five obstacles (clutter_gym.worlds.table.sample).
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np

from clutter_gym.training import load
from clutter_gym.training.config import EVAL_SEED

SHELF_PARTS = 5
SHELF_HALF_WIDTH = 0.2


def where(scene) -> str:
    """"shelf" or "table": where the layout's target lies."""
    centre = np.mean([np.asarray(o.position)[:2] for o in scene.obstacles[:SHELF_PARTS]], axis=0)
    return "shelf" if np.linalg.norm(np.asarray(scene.target[:2]) - centre) < SHELF_HALF_WIDTH else "table"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", required=True, help="a ClutterReach run folder, or pretrained/NAME")
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    agent = load(args.run)
    env = agent.make_env()
    tally: Counter = Counter()
    try:
        for i in range(args.episodes):
            obs, info = env.reset(seed=EVAL_SEED + i)
            place, state, done, touched = where(env.unwrapped.scene), None, False, False
            while not done:
                action, state = agent.predict(obs, state)
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
