"""Hyperparameter YAML, config validation, typed CLI options, and the confidence intervals of evaluations."""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pytest
import yaml

from clutter_gym import ENV_IDS
from clutter_gym.cli import build_parser, main
from clutter_gym.training.commands import train_overrides
from clutter_gym.training.config import PPOHyperparams, TrainConfig, config_for, deep_merge, hyperparams_table
from clutter_gym.training.stats import mean_interval, wilson_interval


def test_shipped_yaml_has_a_default_block_and_valid_blocks_for_every_env():
    table = hyperparams_table()
    assert "default" in table
    for env_id in ENV_IDS:
        config = config_for(env_id)
        assert config.env_id == env_id and config.timesteps > 0


def test_env_block_and_overrides_merge_key_by_key():
    config = config_for("ClutterNav-v1", {"timesteps": 1234, "ppo": {"learning_rate": 1e-3}})
    assert config.timesteps == 1234
    assert config.ppo.learning_rate == 1e-3
    table = hyperparams_table()
    assert config.ppo.n_steps == table["ClutterNav-v1"]["ppo"]["n_steps"]  # env block kept
    assert config.ppo.gamma == table["default"]["ppo"]["gamma"]  # default block kept
    assert config.env_kwargs == table["ClutterNav-v1"]["env_kwargs"]


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ({"ppo": {"learning_rate": -1.0}}, "ppo.learning_rate"),
        ({"ppo": {"gamma": 1.5}}, "ppo.gamma"),
        ({"ppo": {"net_arch": [0]}}, "ppo.net_arch"),
        ({"ppo": {"n_epochs": 2.5}}, "ppo.n_epochs"),
        ({"n_envs": 0}, "n_envs"),
        ({"n_envs": 2, "env_workers": 3}, "env_workers"),
        ({"timesteps": float("nan")}, "timesteps"),
        ({"noise": "loud"}, "noise"),
        ({"ppo": {"batch_size": 10**6}}, "ppo.batch_size"),
        ({"ppo": {"learning_rte": 1e-3}}, "learning_rte"),
        ({"n_env": 2}, "n_env"),
        ({"env_kwargs": {"noise": "harsh"}}, "env_kwargs"),
    ],
)
def test_bad_config_values_name_the_field(override, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        config_for("ClutterNav-v1", override)


def test_config_round_trips_through_a_plain_dict():
    config = config_for("ClutterNav-v1", {"seed": 7, "ppo": {"net_arch": [32, 16]}})
    again = TrainConfig.from_dict(config.to_dict())
    assert again == config and again.ppo.net_arch == (32, 16)


def test_sb3_kwargs_carry_net_arch_as_policy_kwargs():
    kwargs = PPOHyperparams(net_arch=(8, 8), log_std_init=-1.0).sb3_kwargs()
    assert kwargs["policy_kwargs"] == {"net_arch": [8, 8], "log_std_init": -1.0}
    assert "normalize_obs" not in kwargs and "net_arch" not in kwargs


def test_typed_cli_options_become_overrides():
    args = build_parser().parse_args(
        ["train", "--timesteps", "500", "--learning-rate", "0.001", "--net-arch", "32,32", "--no-normalize-obs"]
    )
    overrides = train_overrides(args)
    assert overrides["timesteps"] == 500
    assert overrides["ppo"] == {"learning_rate": 0.001, "net_arch": (32, 32), "normalize_obs": False}


@pytest.mark.parametrize("argv", [["train", "--net-arch", "64,x"], ["train", "--n-envs", "0"],
                                  ["sweep", "--train-noise", "none,loud"], ["eval", "run", "--episodes", "0"]])
def test_cli_rejects_malformed_options(argv, capsys):
    with pytest.raises(SystemExit):
        build_parser().parse_args(argv)
    assert "error" in capsys.readouterr().err


def test_resume_refuses_options_that_would_change_the_config(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["train", "--resume", str(tmp_path), "--seed", "3"])
    assert exit_info.value.code == 2 and "drop --seed" in capsys.readouterr().err


def test_wilson_interval_matches_published_values():
    # Newcombe (1998), table I: 0/10 -> (0, 0.2775); 1/10 -> (0.0179, 0.4042); 10/10 -> (0.7225, 1).
    assert wilson_interval(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    assert wilson_interval(1, 10) == pytest.approx((0.0179, 0.4042), abs=1e-4)
    assert wilson_interval(10, 10) == pytest.approx((0.7225, 1.0), abs=1e-4)


def test_mean_interval_covers_the_true_mean_about_95_percent_of_the_time():
    rng = np.random.default_rng(0)
    trials = 4000
    covered = sum(lo <= 2.0 <= hi for lo, hi in (mean_interval(rng.normal(2.0, 3.0, size=10)) for _ in range(trials)))
    # Binomial(4000, 0.95) has sd 0.0034: 4 sd either side.
    assert abs(covered / trials - 0.95) < 0.014
    assert mean_interval(np.array([3.0])) == (3.0, 3.0)
    assert all(math.isfinite(v) for v in mean_interval(np.array([1.0, 1.0, 1.0])))


def test_a_training_mix_gives_each_training_env_its_share_and_leaves_evaluation_alone():
    from clutter_gym.training.vec_env import build_vec_env

    config = config_for("ClutterNav-v1", {"n_envs": 3, "env_workers": 1,
                                          "train_env_mix": {"obstacle_density": [0.05, 0.2]}})
    assert [config.train_kwargs(i)["obstacle_density"] for i in range(3)] == [0.05, 0.2, 0.05]
    assert "obstacle_density" not in config.make_kwargs()
    venv = build_vec_env(config, seed=0)
    try:
        assert [env.unwrapped.arena.spec.obstacle_density for env in venv.envs] == [0.05, 0.2, 0.05]
    finally:
        venv.close()
    assert TrainConfig.from_dict(config.to_dict()) == config


def test_a_mix_of_two_arguments_gives_the_envs_every_combination_not_pairs_tied_by_index():
    """Three densities and three profiles: pairing values by index would train 0.05 only clean and 0.2 only under
    low-cost; the nine combinations go to envs 0..8 and start over at env 9."""
    config = config_for("ClutterNav-v1", {"n_envs": 16, "train_env_mix": {
        "obstacle_density": [0.05, 0.12, 0.2], "noise": ["none", "nominal", "low-cost"]}})
    pairs = [(config.train_kwargs(i)["obstacle_density"], config.train_kwargs(i)["noise"])
             for i in range(16)]
    assert len(set(pairs[:9])) == 9 and pairs[9:] == pairs[:7]


def test_a_noise_mix_gives_each_training_env_its_profile_and_validation_the_run_s():
    config = config_for("ClutterFly-v1", {"noise": "harsh", "train_env_mix": {"noise": ["none", "harsh"]},
                                          "env_kwargs": {"noise": {"imu": {"latency_steps": 1}}}})
    assert config.train_kwargs(0)["noise"] == {"profile": "none", "imu": {"latency_steps": 1}}
    assert config.train_kwargs(3)["noise"] == {"profile": "harsh", "imu": {"latency_steps": 1}}
    assert config.make_kwargs()["noise"]["profile"] == "harsh"


@pytest.mark.parametrize(("mix", "message"), [({"obstacle_densty": [0.1]}, "train_env_mix key"),
                                              ({"obstacle_density": []}, "non-empty lists"),
                                              ({"noise": ["harsh", "rough"]}, "noise takes profile names"),
                                              ([0.1], "must map gym.make arguments")])
def test_a_bad_training_mix_is_named(mix, message):
    with pytest.raises(ValueError, match=message):
        config_for("ClutterNav-v1", {"train_env_mix": mix})


def test_shipped_hyperparameter_files_are_found_by_name(tmp_path, monkeypatch):
    from clutter_gym.training.config import read_hyperparams_file, shipped_hyperparams, user_settings

    assert "sensors" in shipped_hyperparams()
    args = build_parser().parse_args(["train", "--env", "ClutterNav-v1", "--hyperparams", "sensors"])
    config = config_for("ClutterNav-v1", train_overrides(args))
    assert config.env_kwargs["subgoal_lookahead"] == 0.0  # sensor-only: no subgoal from a planner
    assert config == config_for("ClutterNav-v1", user_settings(read_hyperparams_file("sensors"), "ClutterNav-v1"))
    monkeypatch.chdir(tmp_path)  # a file of the user's own by that name comes first
    (tmp_path / "sensors").write_text("ClutterNav-v1: {timesteps: 77}\n")
    assert read_hyperparams_file("sensors") == {"ClutterNav-v1": {"timesteps": 77}}
    with pytest.raises(FileNotFoundError, match="nor is it a shipped name: .*sensors"):
        read_hyperparams_file("sensor")


def test_the_robust_block_trains_the_fly_residual_under_harsh_with_memory():
    args = build_parser().parse_args(["train", "--env", "ClutterFly-v1", "--hyperparams", "robust"])
    config = config_for("ClutterFly-v1", train_overrides(args))
    assert config.noise == "harsh" and config.frame_stack > 1
    assert config.residual_gain == config_for("ClutterFly-v1").residual_gain  # the shipped residual, trained harsh
    assert config.make_kwargs(noise="harsh")["noise"] == "harsh"
    # its base reads the airframe's thrust estimate and keeps a margin for the command delay
    assert config.env_kwargs["observe_thrust_ratio"] and config.residual_base == {"attitude_gain": 4.0}
    assert config.residual_space == "velocity"


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_sensors_blocks_distil_a_teacher_into_a_student_that_reads_no_map(env_id):
    args = build_parser().parse_args(["train", "--env", env_id, "--hyperparams", "sensors"])
    config = config_for(env_id, train_overrides(args))
    assert config.teacher.name and config.env_kwargs["subgoal_lookahead"] == 0.0
    # the teacher's map-based parts are its own: the env's planner subgoal, or ClutterReach's line-up teacher's
    # planning on the scene, which needs no env argument
    assert config.teacher_kwargs().get("subgoal_lookahead", 0.0) > 0 or config.teacher.name == "line-up"
    # the block stops when the distillation does: no PPO steps after its warm-up and rounds
    assert config.timesteps == config.distill.warmup_steps + config.distill.rounds * config.distill.round_steps


def test_the_nav_student_trains_under_the_reduced_dynamics_and_is_evaluated_under_full_physics():
    args = build_parser().parse_args(["train", "--env", "ClutterNav-v1", "--hyperparams", "sensors"])
    config = config_for("ClutterNav-v1", train_overrides(args))
    assert config.train_env_mix["dynamics"] == ["reduced"]
    assert "dynamics" not in config.env_kwargs  # evaluation, validation and load() make the env's default: physics


def test_the_last_rounds_sensor_only_fly_block_reads_no_map():
    args = build_parser().parse_args(["train", "--env", "ClutterFly-v1", "--hyperparams", "sensors-ppo"])
    config = config_for("ClutterFly-v1", train_overrides(args))
    assert config.env_kwargs["subgoal_lookahead"] == 0.0 and config.env_kwargs["sensors"] == ["lidar"]
    assert config.residual_gain > 0 and config.residual_space == "velocity"


def test_the_last_rounds_sensor_only_reach_block_reads_no_map():
    args = build_parser().parse_args(["train", "--env", "ClutterReach-v1", "--hyperparams", "sensors-ppo"])
    config = config_for("ClutterReach-v1", train_overrides(args))
    assert config.env_kwargs["subgoal_lookahead"] == 0.0 and config.env_kwargs["observe_directions"]
    assert config.residual_gain > 0 and config.train_layouts == 0  # no planning, so no layout pool to plan once


@pytest.mark.parametrize(("overrides", "message"), [
    ({"teacher": {"name": "planner"}}, "needs teacher.name 'line-up'"),
    ({"teacher": {"name": "line-up"}, "env_kwargs": {"control": "ee_position", "subgoal_lookahead": 0.0,
                                                     "observe_directions": True}}, "needs env_kwargs.control"),
])
def test_the_reach_hand_controller_refuses_a_teacher_or_control_it_cannot_use(overrides, message):
    """The shipped Reach student block with one setting changed: the planner teacher answers in joint velocities,
    and the hand controller drives the joints."""
    text = resources.files("clutter_gym.training").joinpath("hyperparams", "sensors.yml").read_text()
    block = yaml.safe_load(text)["ClutterReach-v1"]
    config_for("ClutterReach-v1", block)  # the block itself is valid
    with pytest.raises(ValueError, match=message):
        config_for("ClutterReach-v1", deep_merge(block, overrides))
