"""The ``train``, ``eval``, ``sweep`` and ``report`` sub-commands of ``clutter-gym`` (parsers and handlers).

Parsers import nothing heavy, so ``clutter-gym demo`` works without the ``train`` extra; the handlers import
stable-baselines3 and torch when they run. Handlers check what they were asked first (settings, files, run
folders) and report a mistake there as a :class:`UserError`, which the CLI prints as one line.
"""

from __future__ import annotations

import argparse
import json
import re
import typing
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import fields
from pathlib import Path
from typing import Any

from clutter_gym import ENV_IDS
from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.training.config import EVAL_SEED, PPOHyperparams, deep_merge
from clutter_gym.training.sweep import MIX, UNDER, split_profile
from clutter_gym.util.checks import short_repr
from clutter_gym.util.safe_yaml import load_yaml


class UserError(Exception):
    """A mistake in what the user asked for; the CLI prints it as one ``error:`` line and exits with status 2."""


@contextmanager
def user_errors(*kinds: type[BaseException]) -> Iterator[None]:
    """Treat exceptions of ``kinds`` as user errors, printed as one line; by default the checks' exceptions (bad
    values, missing or occupied folders, unloadable runs)."""
    try:
        yield
    except kinds or (ValueError, FileNotFoundError, FileExistsError) as exc:
        raise UserError(str(exc)) from None


def run_errors() -> AbstractContextManager[None]:
    """Treat what stops training on a run folder as one line: a file it cannot write (a full disk), normalisation
    statistics that are missing or in a pickle nobody said to trust, a folder it may not train in (a link out of
    it), or a model that does not fit the run. Other errors of training keep their tracebacks."""
    from clutter_gym.training.normalizer import UntrustedFileError
    from clutter_gym.training.run_dir import IncompatibleRunError, RunWriteError

    return user_errors(RunWriteError, UntrustedFileError, FileNotFoundError, IncompatibleRunError)


def interrupted(args: argparse.Namespace, exc: KeyboardInterrupt) -> str:
    """What to say when Ctrl-C stopped a command: the step training stood at (a ``TrainingInterrupted`` wrote its
    checkpoint) and how to resume: ``report`` and ``train --resume`` continue the run when run again, a new ``train``
    run through ``--resume``."""
    step = getattr(exc, "step", None)
    said = "interrupted" if step is None else f"interrupted at step {step}"
    folder = getattr(args, "run_folder", None)  # set by run_train once the new run's folder exists
    if args.command == "train" and args.resume is None and folder is not None:
        return f"{said}; run clutter-gym train --resume {folder} to resume"
    if args.command in ("train", "report"):
        return f"{said}; run the same command again to resume"
    return said


def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def profile_list(text: str) -> list[str]:
    """Comma-separated noise profiles, each optionally under a dynamics model (``nominal@reduced``)."""
    names = [t.strip() for t in text.split(",") if t.strip()]
    bad = [n for n in names if not _known(*split_profile(n))]
    if not names or bad:
        raise argparse.ArgumentTypeError(f"must be a comma-separated list of {PROFILE_NAMES}, each optionally "
                                         f"under a dynamics model of {_dynamics_modes()} (none{UNDER}reduced), got "
                                         f"{text!r}")
    return names


def train_profile_list(text: str) -> list[str]:
    """:func:`profile_list` where an entry may be a mix of distinct profiles, such as ``none+nominal``."""
    names = [t.strip() for t in text.split(",") if t.strip()]
    for name in names:
        noise, dynamics = split_profile(name)
        parts = noise.split(MIX)
        if len(set(parts)) != len(parts) or not all(_known(part, dynamics) for part in parts):
            raise argparse.ArgumentTypeError(
                f"must be a comma-separated list of {PROFILE_NAMES}, or of mixes of distinct ones joined by "
                f"{MIX!r} (none{MIX}nominal), each optionally under a dynamics model of {_dynamics_modes()} "
                f"(none{UNDER}reduced), got {text!r}")
    if not names:
        raise argparse.ArgumentTypeError(f"must name at least one profile of {PROFILE_NAMES}, got {text!r}")
    return names


def _known(noise: str, dynamics: str | None) -> bool:
    return noise in PROFILE_NAMES and (dynamics is None or dynamics in _dynamics_modes())


def _dynamics_modes() -> tuple[str, ...]:
    from clutter_gym.dynamics import DYNAMICS_MODES  # the env side: imported only where a profile names a model

    return DYNAMICS_MODES


def _int_tuple(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(t) for t in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be comma-separated integers such as 64,64, got {text!r}") from None


def env_kwarg(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` with a YAML value (``0.05``, ``true``, ``[lidar,imu]``); dotted keys reach into mappings."""
    key, sep, value = text.partition("=")
    if not sep or not re.fullmatch(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*", key):
        raise argparse.ArgumentTypeError(f"must be KEY=VALUE such as obstacle_density=0.05 or "
                                         f"noise.lidar.range_sigma=0.02, got {text!r}")
    try:
        return key, load_yaml(value, f"{key}: {short_repr(value)}")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def nest(pairs: list[tuple[str, Any]] | None) -> dict[str, Any]:
    """``[("noise.lidar.range_sigma", 0.02), ...]`` as nested mappings; later pairs win."""
    nested: dict[str, Any] = {}
    for key, value in pairs or ():
        for part in reversed(key.split(".")):
            value = {part: value}
        nested = deep_merge(nested, value)
    return nested


def field_docs(cls: type) -> dict[str, str]:
    """The one-line descriptions of a dataclass's fields, from the ``Attributes:`` section of its docstring."""
    docs: dict[str, str] = {}
    section = (cls.__doc__ or "").partition("Attributes:")[2]
    for match in re.finditer(r"^\s+(\w+): (.+?)(?=^\s+\w+: |\Z)", section, re.M | re.S):
        docs[match.group(1)] = " ".join(match.group(2).split())
    return docs


def _help(text: str) -> str:
    return text.replace("%", "%%")  # argparse %-formats help strings


def _add_env_kwargs_option(parser: argparse.ArgumentParser, help: str) -> None:
    parser.add_argument("--env-kwargs", dest="env_kwargs", metavar="KEY=VALUE", nargs="+", action="extend",
                        type=env_kwarg, default=None, help=help)


def _add_trust_pickle_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--trust-pickle", action="store_true",
                        help="read a run written by clutter-gym 0.1, whose normalisation statistics are a pickle "
                             "(vecnormalize.pkl): loading a pickle runs any code its author put in it, so only for "
                             "runs you trust; the statistics are then rewritten as vecnormalize.npz")


def add_settings_options(parser: argparse.ArgumentParser) -> None:
    _add_env_kwargs_option(parser, "gym.make arguments on top of the hyperparameter files' env_kwargs, YAML values "
                                   "(obstacle_density=0.05 sensors=[lidar,imu]); noise.SECTION.PARAM=VALUE overrides "
                                   "one noise parameter on top of every profile (noise.lidar.range_sigma=0.02)")
    parser.add_argument("--hyperparams", metavar="FILE.yml", default=None,
                        help="your own hyperparameter file, in the form of the shipped ppo.yml ('default' and "
                             "env-id blocks); it goes on top of the shipped file, and options go on top of it")


def _add_ppo_options(parser: argparse.ArgumentParser) -> None:
    """One typed option per PPOHyperparams field (--learning-rate FLOAT, --net-arch 64,64, --[no-]normalize-obs)."""
    group = parser.add_argument_group("PPO hyperparameters (default: the hyperparameter files)")
    hints, docs = typing.get_type_hints(PPOHyperparams), field_docs(PPOHyperparams)
    for f in fields(PPOHyperparams):
        flag, kind, text = "--" + f.name.replace("_", "-"), hints[f.name], _help(docs[f.name].rstrip("."))
        if kind is bool:
            group.add_argument(flag, dest=f"ppo.{f.name}", action=argparse.BooleanOptionalAction, default=None,
                               help=text)
        elif kind in (int, float):
            group.add_argument(flag, dest=f"ppo.{f.name}", type=kind, default=None, metavar=kind.__name__.upper(),
                               help=text)
        else:
            group.add_argument(flag, dest=f"ppo.{f.name}", type=_int_tuple, default=None, metavar="N,N", help=text)


_TRAIN_KEYS = ("seed", "noise", "timesteps", "n_envs", "checkpoint_every", "final_eval_episodes")


def _given(args: argparse.Namespace) -> dict[str, Any]:
    """The train options given on the command line, by destination (``ppo.*`` for PPO fields)."""
    keys = (*_TRAIN_KEYS, "env_kwargs", "hyperparams", "env", "out")
    return {k: v for k, v in vars(args).items() if v is not None and (k in keys or k.startswith("ppo."))}


def settings(args: argparse.Namespace) -> dict[str, Any]:
    """Config overrides from ``--hyperparams`` and ``--env-kwargs`` (in that order) for ``args.env``."""
    from clutter_gym.training.config import read_hyperparams_file, user_settings

    table = read_hyperparams_file(args.hyperparams) if args.hyperparams else {}
    return deep_merge(user_settings(table, args.env), {"env_kwargs": nest(args.env_kwargs)})


def train_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The file settings, then the options given on the command line, as a config override mapping."""
    overrides = settings(args)
    overrides.update({k: getattr(args, k) for k in _TRAIN_KEYS if getattr(args, k) is not None})
    ppo = {k.split(".", 1)[1]: v for k, v in vars(args).items() if k.startswith("ppo.") and v is not None}
    return deep_merge(overrides, {"ppo": ppo})


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train", help="train PPO into a run folder (or --resume one)",
                       description="Train PPO into a run folder, or continue one with --resume.")
    p.add_argument("--env", choices=ENV_IDS, default=None, help="env id (default ClutterNav-v1)")
    p.add_argument("--timesteps", type=positive_int, default=None, help="total env steps (default from the files)")
    p.add_argument("--n-envs", type=positive_int, default=None, help="parallel envs (default from the files)")
    p.add_argument("--seed", type=int, default=None, help="seeds PPO and the envs (env i gets SEED + i; default 0)")
    p.add_argument("--noise", choices=PROFILE_NAMES, default=None, help="noise profile to train under (default none)")
    p.add_argument("--checkpoint-every", type=positive_int, default=None, help="env steps between checkpoints")
    p.add_argument("--final-eval-episodes", type=int, default=None,
                   help="episodes of the evaluation written to eval.json after training (0: none)")
    p.add_argument("--out", default=None, help="the run folder (default runs/ENV/NOISE-seedSEED)")
    p.add_argument("--resume", metavar="RUN_DIR", default=None,
                   help="continue this run from its newest checkpoint with its saved settings (only --timesteps "
                        "may change)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_trust_pickle_option(p)
    add_settings_options(p)
    _add_ppo_options(p)
    p.set_defaults(handler=run_train)

    p = sub.add_parser("eval", help="evaluate a run under a noise profile: rates and means with 95%% intervals",
                       description="Evaluate a trained run: success and collision rates, cost, return, length and "
                                   "clearance, each with its 95% interval.")
    p.add_argument("run", help="run folder (written by train, or out/main/run by report)")
    p.add_argument("--noise", choices=PROFILE_NAMES, default="none",
                   help="noise profile to evaluate under (the run's noise overrides apply on top)")
    p.add_argument("--episodes", type=positive_int, default=100, help="episodes to roll out")
    p.add_argument("--seed", type=int, default=EVAL_SEED, help="episode i is reset with seed SEED + i")
    _add_env_kwargs_option(p, "change the run's env arguments for this evaluation (obstacle_density=0.2, "
                              "noise.lidar.range_sigma=0.05); the observation and action shapes must stay the same")
    p.add_argument("--json", action="store_true", help="print the summary as JSON (per-episode rows included)")
    p.add_argument("--video", default=None, help="write the first episode to this .gif or .mp4")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_trust_pickle_option(p)
    p.set_defaults(handler=run_eval)

    p = sub.add_parser("sweep", help="sim-to-real sweep: train under profiles, evaluate under profiles, CSV + heatmap",
                       description="Train under each --train-noise profile and seed, evaluate every run under "
                                   "each --eval-noise profile; write sweep.csv and heatmap.png.")
    p.add_argument("--env", choices=ENV_IDS, default="ClutterNav-v1", help="env id")
    p.add_argument("--train-noise", type=train_profile_list, default=["none", "nominal"],
                   help="comma-separated profiles to train under; a+b trains a share of the envs under each, "
                        "a@reduced trains under the reduced dynamics")
    p.add_argument("--eval-noise", type=profile_list, default=["none", "nominal", "harsh"],
                   help="comma-separated profiles to evaluate every run under; a@reduced under the reduced dynamics")
    p.add_argument("--seeds", type=positive_int, default=2, help="training seeds per train profile (0..N-1)")
    p.add_argument("--timesteps", type=positive_int, default=None,
                   help="env steps per training run (default from the files)")
    p.add_argument("--episodes", type=positive_int, default=50, help="evaluation episodes per (run, eval profile)")
    p.add_argument("--out", default="runs/sweep", help="sweep folder (cells, sweep.csv, heatmap.png)")
    p.add_argument("--workers", type=positive_int, default=None, help="cells run at once (default: CPU cores)")
    p.add_argument("--n-envs", type=positive_int, default=None,
                   help="envs per training cell (default from the files; each cell steps them over one worker "
                        "process per core, so --workers 1 gives a cell every core)")
    p.add_argument("--ray-address", default=None,
                   help="run cells as Ray tasks on this cluster ('auto', 'HEAD:6379', 'ray://HEAD:10001', or "
                        "'local' for a local Ray)")
    p.add_argument("--cpus-per-cell", type=positive_int, default=None,
                   help="with --ray-address: CPUs each cell reserves on one node and steps its envs over (default: "
                        "env_workers from the files, or 1 when that is 0); more than the largest node has is an error")
    add_settings_options(p)
    p.set_defaults(handler=run_sweep)

    p = sub.add_parser("report", help="the main job: train PPO, evaluate clean and nominal, write a report",
                       description="The main job: train PPO with the defaults (or resume that run), evaluate it "
                                   "with clean sensors and under the nominal profile, and write report.md, a "
                                   "learning curve and an episode GIF.")
    p.add_argument("--env", choices=ENV_IDS, default="ClutterNav-v1", help="env id")
    p.add_argument("--timesteps", type=positive_int, default=None,
                   help="training budget in env steps (default from the files)")
    p.add_argument("--seed", type=int, default=0, help="training seed")
    p.add_argument("--episodes", type=positive_int, default=100, help="evaluation episodes per profile")
    p.add_argument("--out", default="out/main", help="report folder (the run is OUT/run)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_settings_options(p)
    p.set_defaults(handler=run_report)


def run_train(args: argparse.Namespace) -> int:
    from clutter_gym.training.config import config_for
    from clutter_gym.training.run_dir import RunDir
    from clutter_gym.training.train import check_env_builds, start, train

    with user_errors():
        if args.resume is not None:
            extra = sorted(set(_given(args)) - {"timesteps"})
            if extra:
                flags = ", ".join("--" + k.removeprefix("ppo.").replace("_", "-") for k in extra)
                raise UserError(f"--resume continues the run with its saved settings; only --timesteps may "
                                f"change, so drop {flags}")
            run = RunDir(args.resume)
            check_env_builds(run.read_config())  # a run from someone else: its env is refused here, in one line
        else:
            args.env = args.env or "ClutterNav-v1"
            config = config_for(args.env, train_overrides(args))
            run = start(config, args.out or f"runs/{config.env_id}/{config.noise}-seed{config.seed}")
    print(f"run folder: {run.root}")
    args.run_folder = run.root  # what a new run is resumed from, for the message of an interrupt
    with run_errors():
        summary = train(run, progress=not args.no_progress, timesteps=args.timesteps, trust_pickle=args.trust_pickle)
    if summary is not None:
        print_summary(summary)
    return 0


def run_eval(args: argparse.Namespace) -> int:
    from clutter_gym.training.evaluate import evaluate

    with user_errors():
        summary = evaluate(args.run, noise=args.noise, episodes=args.episodes, seed=args.seed, video=args.video,
                           env_overrides=nest(args.env_kwargs), trust_pickle=args.trust_pickle,
                           progress=not args.no_progress)
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
    from clutter_gym.training.sweep import SweepSpec, check_spec
    from clutter_gym.training.sweep import run_sweep as sweep

    with user_errors():
        spec = SweepSpec(env_id=args.env, train_noise=tuple(args.train_noise), eval_noise=tuple(args.eval_noise),
                         seeds=args.seeds, timesteps=args.timesteps, episodes=args.episodes, n_envs=args.n_envs,
                         settings=settings(args))
        check_spec(spec, Path(args.out))
    with user_errors():
        result = sweep(spec, Path(args.out), workers=args.workers, ray_address=args.ray_address,
                       cpus_per_cell=args.cpus_per_cell)
    print(f"sweep: {result['cells_run']} cells run, {result['cells_skipped']} already done")
    print(f"  {result['csv']}\n  {result['heatmap']}\n  {result['summary']}")
    return 0


def run_report(args: argparse.Namespace) -> int:
    from clutter_gym.training.report import main_job, prepare_run

    with user_errors():
        run = prepare_run(args.env, Path(args.out), timesteps=args.timesteps, seed=args.seed, settings=settings(args))
    with run_errors():
        report = main_job(run, Path(args.out), timesteps=args.timesteps, episodes=args.episodes,
                          progress=not args.no_progress)
    print(Path(report).read_text())
    return 0
