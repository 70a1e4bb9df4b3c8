"""rl-zoo3 trains these envs with the shipped settings: ``--conf-file clutter_gym.training.zoo``."""

from __future__ import annotations

import subprocess
import sys

from clutter_gym import ENV_IDS
from clutter_gym.training.config import config_for
from clutter_gym.training.zoo import hyperparams


def test_the_zoo_blocks_carry_the_shipped_settings():
    assert set(hyperparams) == set(ENV_IDS)
    for env_id, block in hyperparams.items():
        config = config_for(env_id)
        assert block["policy"] == "MultiInputPolicy" and block["n_envs"] == config.n_envs
        assert block["n_timesteps"] == config.timesteps and block["env_kwargs"] == config.make_kwargs()
        assert block["learning_rate"] == config.ppo.learning_rate
        assert block["policy_kwargs"] == {"net_arch": list(config.ppo.net_arch),
                                          "log_std_init": config.ppo.log_std_init}
        assert block["normalize"] == {"norm_obs": config.ppo.normalize_obs, "norm_reward": config.ppo.normalize_reward}
    reach = config_for("ClutterReach-v0")
    assert hyperparams["ClutterReach-v0"]["env_wrapper"] == [
        {"clutter_gym.training.layout_pool.LayoutPool": {"n_layouts": reach.layouts_per_env}},
        {"clutter_gym.training.residual.SubgoalResidual": {"gain": reach.residual_gain}},
    ]
    assert "env_wrapper" not in hyperparams["ClutterNav-v0"]


def test_rl_zoo3_trains_clutter_nav_from_the_shipped_conf_file(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", "ClutterNav-v0", "--gym-packages",
         "clutter_gym", "--conf-file", "clutter_gym.training.zoo", "-n", "128", "--eval-freq", "-1", "--seed", "0",
         "-f", str(tmp_path), "-params", "n_envs:1", "n_steps:64", "batch_size:32", "n_epochs:1"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "'MultiInputPolicy'" in result.stdout
    assert list(tmp_path.glob("ppo/ClutterNav-v0_*/ClutterNav-v0.zip"))
