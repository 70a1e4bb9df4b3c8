"""The ``train``, ``eval``, ``sweep`` and ``report`` sub-commands of ``clutter-gym`` (parsers and handlers).

Parsers import nothing heavy, so ``clutter-gym demo`` works without the ``train`` extra; the handlers import
stable-baselines3 and torch when they run.
"""

from __future__ import annotations

import argparse
import json
import typing
from dataclasses import fields
from pathlib import Path
from typing import Any

from clutter_gym import ENV_IDS
from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.training.config import EVAL_SEED, PPOHyperparams

def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def profile_list(text: str) -> list[str]:
    names = [t.strip() for t in text.split(",") if t.strip()]
    bad = [n for n in names if n not in PROFILE_NAMES]
    if not names or bad:
        raise argparse.ArgumentTypeError(f"must be a comma-separated list of {PROFILE_NAMES}, got {text!r}")
    return names


def _int_tuple(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(t) for t in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be comma-separated integers such as 64,64, got {text!r}") from None


def _add_ppo_options(parser: argparse.ArgumentParser) -> None:
    """One typed option per PPOHyperparams field (--learning-rate FLOAT, --net-arch 64,64, --[no-]normalize-obs)."""
    group = parser.add_argument_group("PPO hyperparameters (override training/hyperparams/ppo.yml)")
    hints = typing.get_type_hints(PPOHyperparams)
    for f in fields(PPOHyperparams):
        flag = "--" + f.name.replace("_", "-")
        kind = hints[f.name]
        if kind is bool:
            group.add_argument(flag, dest=f"ppo.{f.name}", action=argparse.BooleanOptionalAction, default=None)
        elif kind in (int, float):
            group.add_argument(flag, dest=f"ppo.{f.name}", type=kind, default=None, metavar=kind.__name__.upper())
        else:
            group.add_argument(flag, dest=f"ppo.{f.name}", type=_int_tuple, default=None, metavar="N,N")


_TRAIN_KEYS = ("seed", "noise", "timesteps", "n_envs", "checkpoint_every", "final_eval_episodes")


def train_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The options given on the command line, as a config override mapping."""
    overrides: dict[str, Any] = {k: getattr(args, k) for k in _TRAIN_KEYS if getattr(args, k) is not None}
    ppo = {k.split(".", 1)[1]: v for k, v in vars(args).items() if k.startswith("ppo.") and v is not None}
    if ppo:
        overrides["ppo"] = ppo
    return overrides


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train", help="train PPO into a run folder (or --resume one)")
    p.add_argument("--env", choices=ENV_IDS, default=None, help="env id (default ClutterNav-v0)")
    p.add_argument("--timesteps", type=positive_int, default=None, help="total env steps (default from ppo.yml)")
    p.add_argument("--n-envs", type=positive_int, default=None, help="parallel envs (default from ppo.yml)")
    p.add_argument("--seed", type=int, default=None, help="seed (default 0)")
    p.add_argument("--noise", choices=PROFILE_NAMES, default=None, help="noise profile to train under (default none)")
    p.add_argument("--checkpoint-every", type=positive_int, default=None, help="env steps between checkpoints")
    p.add_argument("--final-eval-episodes", type=int, default=None, help="episodes of the evaluation after training")
    p.add_argument("--out", default=None, help="the run folder (default runs/ENV/NOISE-seedSEED)")
    p.add_argument("--resume", metavar="RUN_DIR", default=None,
                   help="continue this run from its newest checkpoint with its saved config (only --timesteps may change)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_ppo_options(p)
    p.set_defaults(handler=run_train)

    p = sub.add_parser("eval", help="evaluate a run under a noise profile: rates and means with 95% intervals")
    p.add_argument("run", help="run folder")
    p.add_argument("--noise", choices=PROFILE_NAMES, default="none", help="noise profile to evaluate under")
    p.add_argument("--episodes", type=positive_int, default=100)
    p.add_argument("--seed", type=int, default=EVAL_SEED, help="episode i is reset with seed SEED + i")
    p.add_argument("--json", action="store_true", help="print the summary as JSON (per-episode rows included)")
    p.add_argument("--video", default=None, help="write the first episode to this .gif or .mp4")
    p.set_defaults(handler=run_eval)

    p = sub.add_parser("sweep", help="sim-to-real sweep: train under profiles, evaluate under profiles, CSV + heatmap")
    p.add_argument("--env", choices=ENV_IDS, default="ClutterNav-v0")
    p.add_argument("--train-noise", type=profile_list, default=["none", "nominal"], help="comma-separated profiles")
    p.add_argument("--eval-noise", type=profile_list, default=["none", "nominal", "harsh"], help="comma-separated profiles")
    p.add_argument("--seeds", type=positive_int, default=2, help="training seeds per train profile (0..N-1)")
    p.add_argument("--timesteps", type=positive_int, default=None, help="env steps per training run (default from ppo.yml)")
    p.add_argument("--episodes", type=positive_int, default=50, help="evaluation episodes per (run, eval profile)")
    p.add_argument("--out", default="runs/sweep", help="sweep folder (cells, sweep.csv, heatmap.png)")
    p.add_argument("--workers", type=positive_int, default=None, help="cells run at once (default: CPU cores)")
    p.add_argument("--n-envs", type=positive_int, default=1, help="envs per training cell")
    p.add_argument("--ray-address", default=None,
                   help="run cells as Ray tasks on this cluster ('auto', 'ray://host:10001', or 'local' for a local Ray)")
    p.set_defaults(handler=run_sweep)

    p = sub.add_parser("report", help="the main job: train PPO, evaluate clean and nominal, write a report")
    p.add_argument("--env", choices=ENV_IDS, default="ClutterNav-v0")
    p.add_argument("--timesteps", type=positive_int, default=None, help="training budget in env steps (default from ppo.yml)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--episodes", type=positive_int, default=100, help="evaluation episodes per profile")
    p.add_argument("--out", default="out/main", help="report folder (the run is RUN/run)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=run_report)


def run_train(args: argparse.Namespace) -> int:
    from clutter_gym.training.config import config_for
    from clutter_gym.training.run_dir import RunDir
    from clutter_gym.training.train import start, train

    overrides = train_overrides(args)
    if args.resume is not None:
        extra = sorted(set(overrides) - {"timesteps"}) + (["--env"] if args.env else []) + (["--out"] if args.out else [])
        if extra:
            raise SystemExit(f"clutter-gym train: --resume continues with the run's saved config; drop {extra}")
        run = RunDir(args.resume)
        run.read_config()
    else:
        config = config_for(args.env or "ClutterNav-v0", overrides)
        run = start(config, args.out or f"runs/{config.env_id}/{config.noise}-seed{config.seed}")
    print(f"run folder: {run.root}")
    summary = train(run, progress=not args.no_progress, timesteps=overrides.get("timesteps"))
    if summary is not None:
        print_summary(summary)
    return 0


def run_eval(args: argparse.Namespace) -> int:
    from clutter_gym.training.evaluate import evaluate

    summary = evaluate(args.run, noise=args.noise, episodes=args.episodes, seed=args.seed, video=args.video)
    if args.json:
        print(json.dumps(summary))
    else:
        print_summary(summary)
    return 0


def print_summary(summary: dict[str, Any]) -> None:
    print(f"{summary['env_id']}: trained under {summary['train_noise']!r}, evaluated under {summary['eval_noise']!r}, "
          f"{summary['episodes']} episodes from seed {summary['seed']} (model at step {summary['model_step']})")
    for name, metric in summary["metrics"].items():
        low, high = metric["ci95"]
        print(f"  {name:<20} {metric['value']:9.3f}   95% CI [{low:.3f}, {high:.3f}]")
    if summary.get("video"):
        print(f"  video                {summary['video']}")


def run_sweep(args: argparse.Namespace) -> int:
    from clutter_gym.training.sweep import SweepSpec, run_sweep as sweep

    spec = SweepSpec(env_id=args.env, train_noise=tuple(args.train_noise), eval_noise=tuple(args.eval_noise),
                     seeds=args.seeds, timesteps=args.timesteps, episodes=args.episodes, n_envs=args.n_envs)
    result = sweep(spec, Path(args.out), workers=args.workers, ray_address=args.ray_address)
    print(f"sweep: {result['cells_run']} cells run, {result['cells_skipped']} already done")
    print(f"  {result['csv']}\n  {result['heatmap']}")
    return 0


def run_report(args: argparse.Namespace) -> int:
    from clutter_gym.training.report import main_job

    report = main_job(args.env, Path(args.out), timesteps=args.timesteps, seed=args.seed, episodes=args.episodes,
                      progress=not args.no_progress)
    print(Path(report).read_text())
    return 0
