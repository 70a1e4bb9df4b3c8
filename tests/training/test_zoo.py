"""rl-zoo3 trains these envs with the shipped settings: the README's command, with the zoo's evaluation on."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym import TRAIN_IDS
from clutter_gym.training.config import config_for
from clutter_gym.training.zoo import hyperparams

# The README's command (docs/training.md); the tests add a small budget and evaluation schedule to it.
ZOO_TRAIN = ["-m", "rl_zoo3.train", "--algo", "ppo", "--gym-packages", "clutter_gym", "--conf-file",
             "clutter_gym.training.zoo"]


def test_the_zoo_blocks_carry_the_shipped_settings():
    assert set(hyperparams) == set(TRAIN_IDS)
    for train_id, block in hyperparams.items():
        config = config_for(TRAIN_IDS[train_id])
        assert block["policy"] == "MultiInputPolicy" and block["n_envs"] == config.n_envs
        assert block["n_timesteps"] == config.timesteps and "env_kwargs" not in block  # the id carries them
        assert block["learning_rate"] == config.ppo.learning_rate
        assert block["policy_kwargs"] == {"net_arch": list(config.ppo.net_arch),
                                          "log_std_init": config.ppo.log_std_init}
        assert block["normalize"] == {"norm_obs": config.ppo.normalize_obs, "norm_reward": config.ppo.normalize_reward}
    reach = config_for("ClutterReach-v1")
    assert hyperparams["ClutterReachTrain-v1"]["env_wrapper"] == [
        {"clutter_gym.training.layout_pool.LayoutPool": {"n_layouts": reach.layouts_per_env}},
        {"clutter_gym.training.residual.SubgoalResidual": {"gain": reach.residual_gain, "space": "action"}},
    ]
    assert "env_wrapper" not in hyperparams["ClutterNavTrain-v1"]


@pytest.mark.parametrize("train_id", list(TRAIN_IDS))
def test_a_train_id_is_its_env_with_the_shipped_arguments(train_id):
    env_id = TRAIN_IDS[train_id]
    shipped = gym.make(train_id)
    direct = gym.make(env_id, **config_for(env_id).make_kwargs())
    assert shipped.spec.max_episode_steps == direct.spec.max_episode_steps
    assert shipped.observation_space == direct.observation_space
    a, _ = shipped.reset(seed=3)
    b, _ = direct.reset(seed=3)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    shipped.close()
    direct.close()


@pytest.mark.parametrize("train_id", list(TRAIN_IDS))
def test_rl_zoo3_trains_evaluates_and_enjoys_each_env(train_id, tmp_path):
    """The zoo's evaluation stays on (its default; a small --eval-freq so it runs within the budget): rl-zoo3 makes
    its evaluation env from the id alone, which is what broke before the Train ids."""
    train = subprocess.run(
        [sys.executable, *ZOO_TRAIN, "--env", train_id, "-n", "512", "--eval-freq", "256", "--eval-episodes", "1",
         "--seed", "0", "-f", str(tmp_path), "-params", "n_envs:2", "n_steps:64", "batch_size:32", "n_epochs:1"],
        capture_output=True, text=True, cwd=tmp_path, timeout=600,
    )
    assert train.returncode == 0, train.stderr[-3000:]
    run = tmp_path / "ppo" / f"{train_id}_1"
    assert (run / "best_model.zip").is_file() and (run / f"{train_id}.zip").is_file()
    with np.load(run / "evaluations.npz") as evaluations:
        assert len(evaluations["timesteps"]) == 2  # at 256 and 512 steps
    enjoy = subprocess.run(
        [sys.executable, "-m", "rl_zoo3.enjoy", "--algo", "ppo", "--env", train_id, "--gym-packages", "clutter_gym",
         "-f", str(tmp_path), "--exp-id", "1", "-n", "100", "--no-render", "--load-best"],
        capture_output=True, text=True, cwd=tmp_path, timeout=600,
    )
    assert enjoy.returncode == 0, enjoy.stderr[-3000:]
