"""The shipped PPO settings in rl-zoo3's hyperparameter format, so the zoo trains these envs as we do.

    python -m rl_zoo3.train --algo ppo --env ClutterNavTrain-v1 --gym-packages clutter_gym \\
        --conf-file clutter_gym.training.zoo

rl-zoo3 imports this module and reads ``hyperparams`` (a block per env id). Its blocks are keyed by the
``*Train-v1`` ids (``clutter_gym.TRAIN_IDS``), which make each env with the env arguments its agent trains with:
rl-zoo3 (2.9) makes its evaluation env without a block's ``env_kwargs``, so settings carried there would reach the
training envs only. The blocks carry the wrappers (the layout pool, the residual on the subgoal pursuit), which
the zoo applies to both.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.envs.registration import load_env_creator

from clutter_gym import TRAIN_IDS
from clutter_gym.training.config import TrainConfig, config_for


def shipped_env(env_id: str, **overrides: Any) -> gym.Env:
    """``env_id``'s env with the env arguments of its block in the hyperparameter files, ``overrides`` on top
    (the entry point of the ``*Train-v1`` ids)."""
    creator = load_env_creator(gym.spec(env_id).entry_point)
    return creator(**{**config_for(env_id).make_kwargs(), **overrides})


def zoo_block(config: TrainConfig) -> dict[str, Any]:
    """One env's rl-zoo3 block: PPO arguments plus the zoo's ``n_timesteps``, ``n_envs``, ``policy``,
    ``normalize``, ``frame_stack`` and ``env_wrapper`` (the layout pool and the residual on the subgoal pursuit)
    keys; the env arguments come with the block's ``*Train-v1`` id."""
    ppo = config.ppo
    block: dict[str, Any] = {
        "n_timesteps": config.timesteps,
        "n_envs": config.n_envs,
        "policy": "MultiInputPolicy",
        **ppo.sb3_kwargs(),
    }
    if config.frame_stack > 1:
        block["frame_stack"] = config.frame_stack
    wrappers: list[dict[str, Any]] = []  # rl-zoo3 wraps every env it makes, its evaluation env too
    if config.train_layouts:
        wrappers.append({"clutter_gym.training.layout_pool.LayoutPool": {"n_layouts": config.layouts_per_env}})
    if config.residual_gain:
        residual = {"gain": config.residual_gain, "space": config.residual_space}
        if config.residual_base:
            residual["base"] = dict(config.residual_base)
        wrappers.append({"clutter_gym.training.residual.SubgoalResidual": residual})
    if wrappers:
        block["env_wrapper"] = wrappers
    if ppo.normalize_obs or ppo.normalize_reward:
        block["normalize"] = {"norm_obs": ppo.normalize_obs, "norm_reward": ppo.normalize_reward}
    return block


hyperparams: dict[str, dict[str, Any]] = {
    train_id: zoo_block(config_for(env_id)) for train_id, env_id in TRAIN_IDS.items()
}
