"""Vectorised envs for training: the clutter env, its episode statistics, and SB3's observation normalisation."""

from __future__ import annotations

import functools
import os
from pathlib import Path
from typing import Any

import gymnasium as gym
from gymnasium import spaces
from gymnasium.wrappers import FilterObservation
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecNormalize

from clutter_gym.training import normalizer
from clutter_gym.training.binned_actions import BinnedActions
from clutter_gym.training.config import TrainConfig
from clutter_gym.training.episode_stats import EpisodeStats
from clutter_gym.training.layout_pool import LayoutPool
from clutter_gym.training.memory import stack_frames
from clutter_gym.training.residual import SubgoalResidual
from clutter_gym.training.scan_memory import MemoryObservation
from clutter_gym.training.statistics_file import float_keys
from clutter_gym.training.worker_vec_env import WorkerVecEnv


def make_env(env_id: str, make_kwargs: dict[str, Any], render_mode: str | None = None, layouts: int = 0,
             residual_gain: float = 0.0, residual_space: str = "action",
             residual_base: dict[str, float] | None = None, teacher: str = "",
             keep: tuple[str, ...] | None = None, scan_memory: str = "", action_bins: int = 0) -> gym.Env:
    """One env with SB3's Monitor and the EpisodeStats wrapper (importable in a fresh worker process); with
    ``layouts`` > 0 it resets from a pool of that many layouts (:class:`LayoutPool`), with a base controller
    (``residual_gain`` > 0, or the velocity interface ``residual_space="velocity"``) it takes residual actions on
    it (:class:`SubgoalResidual`, with the base controller's ``residual_base`` gains); with a ``teacher`` (its env
    arguments already in ``make_kwargs``) its steps carry the teacher's labels (:class:`TeacherLabels`) and only
    the observation entries ``keep`` reach the policy; with a ``scan_memory`` its observations carry the LIDAR's
    memory (:class:`MemoryObservation`); with ``action_bins`` its actions are bins (:class:`BinnedActions`)."""
    import clutter_gym  # noqa: F401  (registers the ids in worker processes)

    env = gym.make(env_id, render_mode=render_mode, **make_kwargs)
    if layouts:
        env = LayoutPool(env, layouts)
    if residual_gain or residual_space != "action":
        env = SubgoalResidual(env, residual_gain, residual_space, residual_base)
    if scan_memory:
        env = MemoryObservation(env, scan_memory)
    if teacher:
        from clutter_gym.training.teachers import TeacherLabels, make_teacher

        env = TeacherLabels(env, make_teacher(env_id, teacher, env, residual_space))
        env = FilterObservation(env, list(keep or env.observation_space.spaces))
    if action_bins:
        env = BinnedActions(env, action_bins)
    return EpisodeStats(Monitor(env))


def build_vec_env(config: TrainConfig, seed: int) -> VecEnv:
    """``config.n_envs`` envs over ``env_workers(config)`` processes, seeded ``seed, seed + 1, ...`` at their first
    reset; with ``config.train_layouts`` each env resets from its share of that many fixed layouts, and env ``i``
    takes its share of ``config.train_env_mix``. A run with a teacher makes them with the teacher's env arguments
    too, and its policy sees the student's entries and ``critic_inputs``."""
    keep = None
    if config.teacher.name:
        keep = (*student_keys(config), *(["memory"] if config.scan_memory else []), *config.critic_inputs)
    fns = [functools.partial(make_env, config.env_id, _train_kwargs(config, i), layouts=config.layouts_per_env,
                             residual_gain=config.residual_gain, residual_space=config.residual_space,
                             residual_base=config.residual_base, teacher=config.teacher.name, keep=keep,
                             scan_memory=config.scan_memory, action_bins=config.action_bins)
           for i in range(config.n_envs)]
    workers = env_workers(config)
    venv: VecEnv = DummyVecEnv(fns) if workers == 1 else WorkerVecEnv(fns, workers)
    venv.seed(seed)
    return venv


def _train_kwargs(config: TrainConfig, index: int) -> dict[str, Any]:
    return {**config.train_kwargs(index), **config.teacher.kwargs(config.env_id)}


def student_keys(config: TrainConfig) -> tuple[str, ...]:
    """The observation entries of the run's own env (what a student reads), sorted."""
    env = gym.make(config.env_id, **config.make_kwargs())
    try:
        return tuple(sorted(env.observation_space.spaces))
    finally:
        env.close()


def env_workers(config: TrainConfig) -> int:
    """The number of env processes: the configured one, or one per CPU core (at most one per env)."""
    return config.env_workers or min(config.n_envs, os.cpu_count() or 1)


def normalize(venv: VecEnv, config: TrainConfig) -> VecEnv:
    """Wrap in VecNormalize when the config asks for observation or reward normalisation."""
    ppo = config.ppo
    if not (ppo.normalize_obs or ppo.normalize_reward):
        return venv
    return VecNormalize(venv, norm_obs=ppo.normalize_obs, norm_reward=ppo.normalize_reward, gamma=ppo.gamma,
                        norm_obs_keys=float_keys(venv.observation_space))


def training_env(config: TrainConfig, seed: int, normalizer_file: Path | None = None) -> VecEnv:
    """The vector env PPO trains on: the envs, their normalisation (fresh, or the statistics saved in
    ``normalizer_file``, a ``vecnormalize.npz`` or a trusted older ``.pkl``, when continuing a run) and the frame
    stack, in that order."""
    venv = build_vec_env(config, seed)
    venv = normalize(venv, config) if normalizer_file is None else normalizer.wrap(venv, normalizer_file, config)
    return stack_frames(venv, config.frame_stack)


def policy_name(space: spaces.Space) -> str:
    return "MultiInputPolicy" if isinstance(space, spaces.Dict) else "MlpPolicy"
