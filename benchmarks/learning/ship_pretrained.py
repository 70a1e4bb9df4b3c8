"""Ship a finished run as an agent inside the package (clutter_gym.training.pretrained): its config.yaml and kept
policy copied into training/pretrained/NAME, evaluated on 100 held-out layouts, and a card.yaml saying how it was
made (the command, and the commit of the tree that trained it, as the run recorded it) and what the package test
holds it to.

    python -m benchmarks.learning.ship_pretrained --run runs/nav --name ClutterNav-v1 \\
        --command "clutter-gym train --env ClutterNav-v1 --seed 0"

The check is the first ``--check-episodes`` of the evaluation's layouts: the test rolls them out again and asks for
at least ``min_success`` successes, the count that a policy of the evaluated success rate falls below with under
1% chance (a binomial quantile). Rollouts are seeded, so the count only moves when the env or the agent changes.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import yaml
from scipy.stats import binom

from clutter_gym.training.config import EVAL_SEED
from clutter_gym.training.evaluate import evaluate
from clutter_gym.training.normalizer import NORMALIZER_FILE
from clutter_gym.training.run_dir import MODEL_FILE, RunDir
from clutter_gym.util.atomic import atomic_folder

ROOT = Path(__file__).resolve().parents[2]
#: one-sided risk that a policy as good as its evaluation fails the package test's check
CHECK_RISK = 0.01


def min_success(rate: float, episodes: int) -> int:
    """The fewest successes in ``episodes`` that a policy of success ``rate`` reaches with probability over
    1 - CHECK_RISK."""
    return int(binom.ppf(CHECK_RISK, episodes, rate))


def ship(run_dir: Path, name: str, command: str, episodes: int, check_episodes: int) -> dict:
    """Copy, evaluate and write the card of one agent; returns the card."""
    run = RunDir(run_dir)
    policy = run.policy_folder()
    summary = evaluate(run_dir, noise="none", episodes=episodes, seed=EVAL_SEED)
    rows = summary["per_episode"]
    checked = sum(bool(r["success"]) for r in rows[:check_episodes])
    success = summary["metrics"]["success_rate"]["value"]
    card = {
        "command": command,
        "commit": run.written_by().get("clutter-gym commit", "not recorded"),  # the tree that trained it
        "env_id": summary["env_id"],
        "model_step": summary["model_step"],
        "evaluation": {"episodes": episodes, "seed": EVAL_SEED, "noise": "none", "success": round(success, 4),
                       "collision": round(summary["metrics"]["collision_rate"]["value"], 4)},
        "check": {"episodes": check_episodes, "min_success": min(checked, min_success(success, check_episodes))},
    }
    with atomic_folder(ROOT / "training" / "pretrained" / name) as out:
        shutil.copy2(run.config_file, out / "config.yaml")
        (out / "model").mkdir()
        for file in (MODEL_FILE, NORMALIZER_FILE):
            if (policy / file).is_file():
                shutil.copy2(policy / file, out / "model" / file)
        (out / "card.yaml").write_text(yaml.safe_dump(card, sort_keys=False))
    return card


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", required=True, type=Path, help="a finished run folder")
    parser.add_argument("--name", required=True, help="the agent's name: load('pretrained/NAME')")
    parser.add_argument("--command", required=True, help="the command that trained the run, for the card")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--check-episodes", type=int, default=10)
    args = parser.parse_args()
    print(yaml.safe_dump(ship(args.run, args.name, args.command, args.episodes, args.check_episodes), sort_keys=False))


if __name__ == "__main__":
    main()
