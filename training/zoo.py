"""The shipped PPO settings in rl-zoo3's hyperparameter format, so the zoo trains these envs as we do.

    python -m rl_zoo3.train --algo ppo --env ClutterNav-v0 --gym-packages clutter_gym \\
        --conf-file clutter_gym.training.zoo

rl-zoo3 imports this module and reads ``hyperparams`` (a block per env id). Without it the zoo falls back to
its ``default`` block, whose ``MlpPolicy`` cannot take these envs' Dict observations.
"""

from __future__ import annotations

from typing import Any

from clutter_gym import ENV_IDS
from clutter_gym.training.config import TrainConfig, config_for


def zoo_block(config: TrainConfig) -> dict[str, Any]:
    """One env's rl-zoo3 block: PPO arguments plus the zoo's ``n_timesteps``, ``n_envs``, ``policy``,
    ``normalize``, ``frame_stack``, ``env_kwargs`` and ``env_wrapper`` (the layout pool and the residual on the
    subgoal pursuit) keys."""
    ppo = config.ppo
    block: dict[str, Any] = {
        "n_timesteps": config.timesteps,
        "n_envs": config.n_envs,
        "policy": "MultiInputPolicy",
        **ppo.sb3_kwargs(),
        "env_kwargs": config.make_kwargs(),
    }
    if config.frame_stack > 1:
        block["frame_stack"] = config.frame_stack
    wrappers: list[dict[str, Any]] = []  # rl-zoo3 wraps every env it makes, its evaluation env too
    if config.train_layouts:
        wrappers.append({"clutter_gym.training.layout_pool.LayoutPool": {"n_layouts": config.layouts_per_env}})
    if config.residual_gain:
        wrappers.append({"clutter_gym.training.residual.SubgoalResidual": {"gain": config.residual_gain}})
    if wrappers:
        block["env_wrapper"] = wrappers
    if ppo.normalize_obs or ppo.normalize_reward:
        block["normalize"] = {"norm_obs": ppo.normalize_obs, "norm_reward": ppo.normalize_reward}
    return block


hyperparams: dict[str, dict[str, Any]] = {env_id: zoo_block(config_for(env_id)) for env_id in ENV_IDS}
