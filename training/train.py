"""Train PPO on a clutter-gym env into a run folder; resume a killed run from its newest checkpoint."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import CallbackList
from stable_baselines3.common.logger import configure
from stable_baselines3.common.vec_env import VecEnv

from clutter_gym.training.callbacks import BestPolicyKeeper, RunMonitor
from clutter_gym.training.config import EVAL_SEED, TrainConfig
from clutter_gym.training.evaluate import evaluate
from clutter_gym.training.run_dir import NORMALIZER_FILE, RunDir
from clutter_gym.training.vec_env import policy_name, training_env
from clutter_gym.util.atomic import write_text_atomically


def check_env_builds(config: TrainConfig) -> None:
    """Make and close the config's env once, so a bad env argument fails here, named, not in a worker process.

    Raises:
        ValueError: the env refused its arguments.
    """
    try:
        gym.make(config.env_id, **config.make_kwargs()).close()
    except TypeError as exc:  # a value of the wrong type that the env did not check itself
        raise ValueError(f"env_kwargs {config.env_kwargs} do not build {config.env_id}: {exc}") from None


def start(config: TrainConfig, out: str | Path) -> RunDir:
    """A new run folder for ``config``; refuses a folder that already holds a run (resume that instead).

    Raises:
        FileExistsError: ``out`` holds a run.
        ValueError: the config's env cannot be made with its arguments.
    """
    run = RunDir(out)
    if run.config_file.exists():
        raise FileExistsError(f"{run.root} already holds a run; pass --resume {run.root} to continue it, "
                              "or choose another --out")
    check_env_builds(config)
    run.root.mkdir(parents=True, exist_ok=True)
    run.write_config(config)
    return run


def build_model(config: TrainConfig, venv: VecEnv) -> PPO:
    """A fresh PPO on ``venv`` with the config's hyperparameters and seed (on the CPU)."""
    return PPO(policy_name(venv.observation_space), venv, seed=config.seed, device="cpu", verbose=0,
               **config.ppo.sb3_kwargs())


def train(run: RunDir, progress: bool = True, timesteps: int | None = None) -> dict[str, Any] | None:
    """Train (or continue) the run in ``run`` up to its configured timesteps, then save and evaluate.

    With ``validate_every`` set, the policy is validated on held-out layouts on that schedule and the best one
    is kept in ``best/``; the final evaluation (like ``load()``) uses that one.

    A run with checkpoints continues from the newest one, with the config saved in the folder: the steps after
    that checkpoint are redone (and their episode rows dropped), so a killed run loses at most one checkpoint
    interval. ``timesteps`` raises the run's total (to extend a finished run). The continued run draws new env
    seeds, so it is not bit-identical to an uninterrupted one.

    Returns:
        The final evaluation summary (also written to ``eval.json``), or None if ``final_eval_episodes`` is 0.
    """
    config = run.read_config()
    if timesteps is not None and timesteps != config.timesteps:
        config = TrainConfig.from_dict({**config.to_dict(), "timesteps": timesteps})
        run.write_config(config)
    torch.set_num_threads(1)  # small MLPs: threads only fight the env workers for the cores
    latest = run.latest_checkpoint()
    done = latest[0] if latest else 0
    normalizer_file = latest[1] / NORMALIZER_FILE if latest else None
    venv = training_env(config, seed=config.seed + done, normalizer_file=normalizer_file)
    try:
        if latest is None:
            model = build_model(config, venv)
        else:
            step, folder = latest
            model = PPO.load(folder / "model.zip", env=venv, device="cpu")
            model.set_random_seed(config.seed + step)
            run.truncate_episodes(step)
        model.set_logger(configure(str(run.tb_dir), ["tensorboard"]))
        remaining = config.timesteps - model.num_timesteps
        callbacks = [RunMonitor(run, config, progress)]
        if config.validate_every:
            callbacks.append(BestPolicyKeeper(run, config))
        if remaining > 0:
            t0 = time.perf_counter()
            model.learn(remaining, callback=CallbackList(callbacks), reset_num_timesteps=latest is None)
            run.add_training_time(time.perf_counter() - t0, model.num_timesteps)
        run.save_model(model, model.get_vec_normalize_env(), run.model_dir)
    finally:
        venv.close()
    if config.final_eval_episodes == 0:
        return None
    summary = evaluate(run.root, noise=config.noise, episodes=config.final_eval_episodes,
                       seed=config.seed + EVAL_SEED)
    write_text_atomically(run.eval_file, json.dumps(summary, indent=2))
    return summary
