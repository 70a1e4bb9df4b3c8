"""Train PPO on a clutter-gym env into a run folder; resume a killed run from its newest checkpoint."""

from __future__ import annotations

import dataclasses
import json
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import torch
from gymnasium import spaces
from sb3_contrib import RecurrentPPO
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import CallbackList
from stable_baselines3.common.logger import configure
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from clutter_gym.training.agent import env_spaces
from clutter_gym.training.callbacks import BestPolicyKeeper, RunMonitor
from clutter_gym.training.config import EVAL_SEED, TrainConfig
from clutter_gym.training.distill import Distiller
from clutter_gym.training.evaluate import evaluate
from clutter_gym.training.normalizer import NORMALIZER_FILE, normalizer_path, read_statistics
from clutter_gym.training.policy_file import load_ppo, saved_step
from clutter_gym.training.privileged import DistilledPPO, LabelRecorder, PrivilegedCriticPolicy
from clutter_gym.training.recurrent_policy import recurrent_policy
from clutter_gym.training.run_dir import MODEL_FILE, IncompatibleRunError, RunDir
from clutter_gym.training.scan_features import SCAN_KEY
from clutter_gym.training.scan_memory import MEMORY_KEY
from clutter_gym.training.vec_env import policy_name, training_env
from clutter_gym.util.atomic import write_text_atomically


class TrainingInterrupted(KeyboardInterrupt):
    """Training was interrupted (Ctrl-C) and a checkpoint of where it stood was written, as rl-zoo3 saves on an
    interrupt: resuming the run continues from ``step``, the env steps trained.
    """

    def __init__(self, step: int) -> None:
        super().__init__(f"interrupted at step {step}")
        self.step = step


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


def build_model(config: TrainConfig, venv: VecEnv) -> OnPolicyAlgorithm:
    """A fresh PPO on ``venv`` with the config's hyperparameters and seed (on the CPU): sb3-contrib's RecurrentPPO
    for a recurrent policy; with a teacher, the :class:`DistilledPPO` whose actor the distillation fits (and whose
    critic reads ``critic_inputs``)."""
    kwargs = config.ppo.sb3_kwargs()
    if config.recurrent:  # a student's DAgger rounds fit its actor; the LSTM critic serves PPO without a teacher
        policy = recurrent_policy(isinstance(venv.observation_space, spaces.Dict))
        return RecurrentPPO(policy, venv, seed=config.seed, device="cpu", verbose=0, **kwargs)
    if not config.teacher.name:
        return PPO(policy_name(venv.observation_space), venv, seed=config.seed, device="cpu", verbose=0, **kwargs)
    kwargs["policy_kwargs"]["critic_inputs"] = config.critic_inputs
    if config.ppo.scan_conv and config.scan_memory == "polar":  # the memory, beam by beam, as a second channel
        kwargs["policy_kwargs"]["scans"] = [SCAN_KEY, MEMORY_KEY]
    return DistilledPPO(PrivilegedCriticPolicy, venv, seed=config.seed, device="cpu", verbose=0,
                        **distilled_kwargs(config), **kwargs)


def distilled_kwargs(config: TrainConfig) -> dict[str, Any]:
    """:class:`DistilledPPO`'s own arguments for the run of ``config``."""
    settings = config.distill
    return {"bc_weight": settings.bc_weight, "bc_steps": settings.bc_steps, "start_step": settings.steps,
            "recorder": LabelRecorder(), "action_bins": config.action_bins}


def train(run: RunDir, progress: bool = True, timesteps: int | None = None, trust_pickle: bool = False,
          env_workers: int | None = None) -> dict[str, Any] | None:
    """Train (or continue) the run in ``run`` up to its configured timesteps, then save and evaluate.

    With ``validate_every`` set, the policy is validated on held-out layouts on that schedule and the best one
    is kept in ``best/``; the final evaluation (like ``load()``) uses that one.

    A run with checkpoints continues from the newest complete one (:func:`resume_point`), with the config saved in
    the folder: the steps after it are redone and their episode and validation rows dropped, so a killed run loses
    at most one checkpoint interval; an interrupted one (Ctrl-C) writes a checkpoint first and loses nothing. A
    run killed before its first checkpoint starts over, saying so. A finished
    run is left as it is unless ``timesteps`` raises its total; it then continues from its final model. The
    continued run draws new env seeds, so it is not bit-identical to an uninterrupted one.

    Args:
        trust_pickle: continue a run written by clutter-gym 0.1, whose normalisation statistics are a pickle.
        env_workers: processes that step the training envs this time (None: the config's); speed only.

    Returns:
        The final evaluation summary (also written to ``eval.json``), or None if ``final_eval_episodes`` is 0 (for a
        finished run left as it is: its ``eval.json``, if any).

    Raises:
        FileNotFoundError: the statistics of a run trained with normalisation are missing from its newest model.
        UntrustedFileError: they are a pickle and ``trust_pickle`` is False.
        IncompatibleRunError: the model to continue from does not fit the run's config (its weights' shapes).
        RunWriteError: a checkpoint or the final model could not be written.
        TrainingInterrupted: training was interrupted; the checkpoint of its step was written.
        IncompatibleRunError: the run cannot be read, or an entry of its folder is a symbolic link.
    """
    config = run.read_config()
    run.check_own_files()
    if timesteps is not None and timesteps != config.timesteps:
        config = TrainConfig.from_dict({**config.to_dict(), "timesteps": timesteps})
        run.write_config(config)
    torch.set_num_threads(1)  # small MLPs: threads only fight the env workers for the cores
    point = resume_point(run, config, trust_pickle)
    if env_workers is not None:
        config = dataclasses.replace(config, env_workers=min(env_workers, config.n_envs))
    done = point[0] if point else 0
    if run.is_finished() and done >= config.timesteps:
        _say(f"{run.root} finished training at step {done}: nothing to resume (pass --timesteps above {done} to "
             "train it further)")
        return json.loads(run.eval_file.read_text()) if run.eval_file.is_file() else None
    _forget_after(run, done)
    venv = training_env(config, seed=config.seed + done, normalizer_file=point[2] if point else None)
    try:
        if point is None:
            model = build_model(config, venv)
        else:
            try:
                model = load_ppo(point[1] / MODEL_FILE, config, venv.observation_space, venv.action_space, env=venv,
                                 **(distilled_kwargs(config) if config.teacher.name and not config.recurrent else {}))
            except ValueError as exc:
                raise IncompatibleRunError(f"{point[1]} cannot be continued from: {exc}") from None
            model.set_random_seed(config.seed + done)
        model.set_logger(configure(str(run.tb_dir), ["tensorboard"]))
        if config.teacher.name and len(run.read_distill_rows()) < config.distill.rounds:
            try:
                Distiller(run, config, model, venv, progress).run_rounds()
            except KeyboardInterrupt:  # the round under way is dropped: its checkpoint would hold half a round
                rows = run.read_distill_rows()
                raise TrainingInterrupted(int(rows[-1]["step"]) if rows else 0) from None
        remaining = config.timesteps - model.num_timesteps
        callbacks = [RunMonitor(run, config, progress)]
        if config.validate_every:
            callbacks.append(BestPolicyKeeper(run, config))
        if isinstance(model, DistilledPPO):
            callbacks.append(model.recorder)
        if remaining > 0:
            if point is not None:
                _say(f"continuing from the checkpoint of step {done}")
            t0 = time.perf_counter()
            callback = CallbackList(callbacks)
            try:
                model.learn(remaining, callback=callback, reset_num_timesteps=model.num_timesteps == 0)
            except KeyboardInterrupt:
                callback.on_training_end()  # the progress bar and the episode log closed before the checkpoint
                run.save_checkpoint(model, model.get_vec_normalize_env(), model.num_timesteps, config.keep_checkpoints)
                run.add_training_time(time.perf_counter() - t0, model.num_timesteps)
                raise TrainingInterrupted(model.num_timesteps) from None
            run.add_training_time(time.perf_counter() - t0, model.num_timesteps)
        run.save_model(model, model.get_vec_normalize_env(), run.model_dir)
    finally:
        venv.close()
    if config.final_eval_episodes == 0:
        return None
    summary = evaluate(run.root, noise=config.noise, episodes=config.final_eval_episodes,
                       seed=config.seed + EVAL_SEED, progress=progress)
    write_text_atomically(run.eval_file, json.dumps(summary, indent=2))
    return summary


def resume_point(run: RunDir, config: TrainConfig, trust_pickle: bool = False) -> tuple[int, Path, Path | None] | None:
    """``(step, model folder, statistics file or None)`` of the newest model the run can continue from: its final
    model or a checkpoint. One that cannot be read (a truncated ``model.zip``, say) is removed, saying so, and the
    one before it is tried; None when there is none.

    Raises:
        FileNotFoundError: the run was trained with normalisation and the newest model's statistics are missing
            (its policy cannot continue on fresh statistics).
        UntrustedFileError: the statistics are a pickle and ``trust_pickle`` is False.
    """
    candidates = list(run.checkpoints())
    observation_space = None  # the env's, made once a candidate holds statistics to check against it
    if run.is_finished():
        try:
            candidates.append((saved_step(run.model_dir / MODEL_FILE), run.model_dir))
        except ValueError as exc:
            _say(f"the final model cannot be continued from: {exc}")
    for step, folder in sorted(candidates, key=lambda c: (c[0], c[1] == run.model_dir), reverse=True):
        statistics = normalizer_path(folder, trust_pickle)
        if statistics is None and (config.ppo.normalize_obs or config.ppo.normalize_reward):
            raise FileNotFoundError(f"{folder / NORMALIZER_FILE} is missing: the run was trained with normalisation "
                                    "and cannot continue on fresh statistics")
        try:
            if saved_step(folder / MODEL_FILE) != step and folder != run.model_dir:
                raise ValueError(f"its model.zip is not of step {step}")
            if statistics is not None:
                if observation_space is None:
                    observation_space = env_spaces(config)[0]
                read_statistics(statistics, config, observation_space)
        except ValueError as exc:
            if folder == run.model_dir:  # the final model is kept: it is what load() and eval use
                _say(f"{folder} cannot be continued from ({exc}); trying the newest checkpoint")
                continue
            _say(f"{folder} cannot be continued from ({exc}): removed, trying the one before it")
            shutil.rmtree(folder, ignore_errors=True)
            continue
        return step, folder, statistics
    return None


def _forget_after(run: RunDir, step: int) -> None:
    """Drop what the run logged after ``step``, which training is about to redo, and say what was dropped."""
    dropped = run.truncate_episodes(step)
    if step == 0 and dropped:
        _say(f"{run.root} has no checkpoint to continue from: starting over from step 0 (dropped the {dropped} "
             "episode rows of the attempt before)")
    run.truncate_distill_rows(step)
    if run.truncate_validations(step):
        _say(f"{run.best_dir} was saved after step {step}, which is being redone: removed")


def _say(message: str) -> None:
    print(f"clutter-gym train: {message}", file=sys.stderr, flush=True)
