"""Vectorised envs for training: the clutter env, its episode statistics, and SB3's observation normalisation."""

from __future__ import annotations

import functools
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv, VecNormalize

from clutter_gym.training.config import TrainConfig
from clutter_gym.training.episode_stats import EpisodeStats


def make_env(env_id: str, make_kwargs: dict[str, Any], render_mode: str | None = None) -> gym.Env:
    """One env with SB3's Monitor and the EpisodeStats wrapper (importable in a fresh worker process)."""
    import clutter_gym  # noqa: F401  (registers the ids in SubprocVecEnv workers)

    return EpisodeStats(Monitor(gym.make(env_id, render_mode=render_mode, **make_kwargs)))


def build_vec_env(config: TrainConfig, seed: int) -> VecEnv:
    """``config.n_envs`` envs (worker processes above 1), seeded ``seed, seed + 1, ...`` at their first reset."""
    factory = functools.partial(make_env, config.env_id, config.make_kwargs())
    fns = [factory] * config.n_envs
    venv: VecEnv = DummyVecEnv(fns) if config.n_envs == 1 else SubprocVecEnv(fns)
    venv.seed(seed)
    return venv


def float_keys(space: spaces.Space) -> list[str] | None:
    """Keys of the float Box entries of a Dict space (images stay unnormalised); None for a non-Dict space."""
    if not isinstance(space, spaces.Dict):
        return None
    return [k for k, s in space.spaces.items() if isinstance(s, spaces.Box) and np.issubdtype(s.dtype, np.floating)]


def normalize(venv: VecEnv, config: TrainConfig) -> VecEnv:
    """Wrap in VecNormalize when the config asks for observation or reward normalisation."""
    ppo = config.ppo
    if not (ppo.normalize_obs or ppo.normalize_reward):
        return venv
    return VecNormalize(venv, norm_obs=ppo.normalize_obs, norm_reward=ppo.normalize_reward, gamma=ppo.gamma,
                        norm_obs_keys=float_keys(venv.observation_space))


def policy_name(space: spaces.Space) -> str:
    return "MultiInputPolicy" if isinstance(space, spaces.Dict) else "MlpPolicy"
