"""The command line as a user meets it: help everywhere, one-line errors with exit status 2, settings from options."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from clutter_gym.cli import build_parser, main
from clutter_gym.training.commands import env_kwarg, nest, settings, train_overrides
from clutter_gym.training.config import config_for

TINY = ["--timesteps", "64", "--n-envs", "1", "--checkpoint-every", "64", "--final-eval-episodes", "0",
        "--n-steps", "64", "--batch-size", "32", "--n-epochs", "1", "--no-progress"]


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    (action,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "clutter_gym.cli", *args], capture_output=True, text=True)


@pytest.mark.parametrize("command", ["", "demo", "profiles", "train", "eval", "sweep", "report"])
def test_help_works_for_the_top_level_and_every_subcommand(command):
    result = _cli(*([command] if command else []), "--help")
    assert result.returncode == 0 and result.stdout.startswith("usage: clutter-gym") and not result.stderr
    if command in ("eval", "sweep", "report", "train"):
        assert "--env-kwargs" in result.stdout or command == "eval" and "KEY=VALUE" in result.stdout


@pytest.mark.parametrize("command", sorted(_subparsers()))
def test_every_option_has_help_text(command):
    parser = _subparsers()[command]
    missing = [a.dest for a in parser._actions if not a.help]
    assert missing == []


def test_ppo_options_take_their_help_from_the_dataclass_field_docs():
    text = _subparsers()["train"].format_help()
    assert "--gae-lambda FLOAT" in text and "GAE bias/variance trade-off" in text
    assert "--net-arch N,N" in text and "hidden layer sizes of both the policy and the value" in text


def _one_line_error(result: subprocess.CompletedProcess, *fragments: str) -> str:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert lines[0].startswith("clutter-gym") and ": error: " in lines[0]
    for fragment in fragments:
        assert fragment in lines[0]
    return lines[0]


@pytest.mark.parametrize("args, fragments", [
    (["train", "--timesteps", "0"], ["--timesteps", "positive integer"]),
    (["train", "--learning-rate", "5"], ["ppo.learning_rate", "(0.0, 1.0]"]),
    (["train", "--env-kwargs", "obstacle_density"], ["--env-kwargs", "KEY=VALUE"]),
    (["train", "--env-kwargs", "bogus=1"], ["['bogus']", "allowed: ['arena_size'", "'obstacle_density'"]),
    (["train", "--env-kwargs", "obstacle_density=0.9"], ["obstacle_density must be in [0, 0.3]"]),
    (["train", "--env-kwargs", "noise.lidar.range_sigma=-1"], ["lidar.range_sigma", "[0.0, 1.0]"]),
    (["train", "--hyperparams", "missing.yml"], ["missing.yml", "does not exist"]),
    (["train", "--resume", "no/such/run"], ["no/such/run is not a run folder"]),
    (["eval", "no/such/run"], ["no/such/run is not a run folder"]),
    (["eval", "no/such/run", "--noise", "loud"], ["--noise", "invalid choice"]),
    (["sweep", "--env-kwargs", "n_rays=many"], ["n_rays must be a number, got 'many'"]),
    (["report", "--seeds", "3"], ["unrecognized arguments: --seeds"]),
])
def test_user_errors_are_one_line_with_exit_status_2(args, fragments):
    _one_line_error(_cli(*args), *fragments)


def test_a_bad_hyperparameter_file_names_the_block_or_field(tmp_path):
    bad_block = tmp_path / "blocks.yml"
    bad_block.write_text("ClutterNavv0:\n  timesteps: 10\n")
    _one_line_error(_cli("train", "--hyperparams", str(bad_block)), "['ClutterNavv0']", "'default'")
    bad_field = tmp_path / "field.yml"
    bad_field.write_text("default:\n  ppo:\n    learning_rat: 0.1\n")
    _one_line_error(_cli("train", "--hyperparams", str(bad_field)), "['learning_rat']", "'learning_rate'")
    not_yaml = tmp_path / "broken.yml"
    not_yaml.write_text("default: [unclosed\n")
    _one_line_error(_cli("report", "--hyperparams", str(not_yaml)), "not valid YAML")


def test_env_kwargs_parse_yaml_values_and_dotted_keys():
    pairs = [env_kwarg(t) for t in ("obstacle_density=0.05", "sensors=[lidar, imu]", "terminate_on_collision=true",
                                     "noise.lidar.range_sigma=0.02", "noise.lidar.rate_hz=10",
                                     "noise.imu.latency_steps=0")]
    assert nest(pairs) == {"obstacle_density": 0.05, "sensors": ["lidar", "imu"], "terminate_on_collision": True,
                           "noise": {"lidar": {"range_sigma": 0.02, "rate_hz": 10}, "imu": {"latency_steps": 0}}}
    assert nest([("a", 1), ("a", 2)]) == {"a": 2}  # the last one wins
    for text in ("=1", "a b=1", "noise..lidar=1", "x"):
        with pytest.raises(argparse.ArgumentTypeError, match="KEY=VALUE"):
            env_kwarg(text)


def test_settings_layer_shipped_file_then_user_file_then_options(tmp_path):
    user = tmp_path / "mine.yml"
    user.write_text(yaml.safe_dump({
        "default": {"n_envs": 2, "ppo": {"learning_rate": 1e-3, "gamma": 0.95}},
        "ClutterNav-v1": {"env_kwargs": {"obstacle_density": 0.05, "noise": {"lidar": {"range_sigma": 0.02}}}},
    }))
    args = build_parser().parse_args(["train", "--hyperparams", str(user), "--gamma", "0.9",
                                      "--env-kwargs", "noise.lidar.dropout_prob=0.1", "lidar_range=3"])
    args.env = "ClutterNav-v1"
    config = config_for("ClutterNav-v1", train_overrides(args))
    shipped = config_for("ClutterNav-v1")
    assert config.n_envs == 2 and config.ppo.learning_rate == 1e-3 and config.ppo.gamma == 0.9
    assert config.ppo.n_steps == shipped.ppo.n_steps  # untouched keys keep the shipped file's values
    assert config.env_kwargs == {**shipped.env_kwargs, "obstacle_density": 0.05, "lidar_range": 3,
                                 "noise": {"lidar": {"range_sigma": 0.02, "dropout_prob": 0.1}}}
    kwargs = config.make_kwargs(noise="harsh")
    assert kwargs["noise"] == {"profile": "harsh", "lidar": {"range_sigma": 0.02, "dropout_prob": 0.1}}
    reach = build_parser().parse_args(["sweep", "--env", "ClutterReach-v1", "--hyperparams", str(user)])
    assert settings(reach) == {"n_envs": 2, "ppo": {"learning_rate": 1e-3, "gamma": 0.95}, "env_kwargs": {}}


def test_train_with_env_kwargs_trains_under_custom_noise_and_resume_refuses_changes(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", *TINY, "--out", str(out), "--env-kwargs", "obstacle_density=0.05",
                 "noise.lidar.range_sigma=0.03"]) == 0
    saved = yaml.safe_load((out / "config.yaml").read_text())
    assert saved["env_kwargs"]["obstacle_density"] == 0.05
    assert saved["env_kwargs"]["noise"] == {"lidar": {"range_sigma": 0.03}}
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(["train", "--resume", str(out), "--learning-rate", "1e-3", "--env-kwargs", "n_rays=8"])
    err = capsys.readouterr().err.strip()
    assert exit_info.value.code == 2 and len(err.splitlines()) == 1
    assert "only --timesteps may change, so drop --env-kwargs, --learning-rate" in err
    with pytest.raises(SystemExit) as exit_info:
        main(["train", *TINY, "--out", str(out)])
    assert exit_info.value.code == 2 and f"--resume {out}" in capsys.readouterr().err


def test_report_refuses_a_run_with_other_settings(tmp_path, capsys):
    from clutter_gym.training.report import prepare_run

    run = prepare_run("ClutterNav-v1", tmp_path, timesteps=64, seed=0,
                      settings={"env_kwargs": {"obstacle_density": 0.05}})
    assert prepare_run("ClutterNav-v1", tmp_path, timesteps=128, seed=0,
                       settings={"env_kwargs": {"obstacle_density": 0.05}}).root == run.root  # a new budget is fine
    with pytest.raises(SystemExit) as exit_info:
        main(["report", "--out", str(tmp_path), "--env-kwargs", "obstacle_density=0.1"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2
    assert "env_kwargs.obstacle_density: 0.05 in the run, 0.1 asked" in err and "another --out" in err


def test_demo_refuses_envs_without_a_scripted_policy(capsys):
    """Every clutter-gym env has a scripted demo; another id is refused by argparse, in one line."""
    with pytest.raises(SystemExit) as exit_info:
        build_parser().parse_args(["demo", "--env", "CartPole-v1"])
    err = capsys.readouterr().err.strip()
    assert exit_info.value.code == 2 and "--env" in err and "ClutterReach-v1" in err and len(err.splitlines()) == 1


def test_the_reach_demo_plans_to_the_target_and_writes_a_gif(tmp_path, capsys):
    assert main(["demo", "--env", "ClutterReach-v1", "--seed", "1", "--out", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["policy"].startswith("scripted joint-space planner")
    assert summary["success"] and summary["contact_steps"] == 0
    assert Path(summary["gif"]).stat().st_size > 0


def _demo_robots() -> list[tuple[str, str]]:
    from clutter_gym.cli import DEMOS
    from clutter_gym.robots.registry import registered

    return [(env_id, robot) for env_id, demo in DEMOS.items() for robot in registered(demo.robot_kind)]


@pytest.mark.parametrize("env_id, robot", _demo_robots())
def test_the_default_demo_moves_every_registered_robot_to_its_goal(env_id, robot, tmp_path, capsys):
    """A demo shows the env working on its defaults: the robot (the point the frames ring) moves and arrives."""
    assert main(["demo", "--env", env_id, "--robot", robot, "--frame-every", "1000", "--out", str(tmp_path),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["robot"] == robot and summary["no_plan"] is None
    assert summary["moved_m"] > 0.1 and summary["success"], summary


def test_a_layout_without_a_plan_is_said_so_and_the_default_demo_shows_one_with_a_plan(tmp_path, capsys):
    """Seed 0 of ClutterReach-v1 is a layout the joint planner finds no path for (if it ever does, pick another)."""
    assert main(["demo", "--env", "ClutterReach-v1", "--seed", "0", "--frame-every", "1000", "--out",
                 str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "the planner found no path" in out and "moved          0.00 m" in out
    assert main(["demo", "--env", "ClutterReach-v1", "--frame-every", "1000", "--out", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["seed"] == 1 and summary["skipped_seeds"] == {"0": "the planner found no path"}
    assert summary["moved_m"] > 0.1 and summary["success"]


def test_the_demo_refuses_a_robot_of_another_kind_in_one_line(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["demo", "--env", "ClutterReach-v1", "--robot", "husky"])
    err = capsys.readouterr().err.strip()
    assert exit_info.value.code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith("clutter-gym demo: error: ") and "robot 'husky' is a wheeled base" in err


def test_the_fly_demo_flies_the_planned_path_to_the_goal_and_writes_a_gif(tmp_path, capsys):
    assert main(["demo", "--env", "ClutterFly-v1", "--seed", "1", "--frame-every", "10", "--out", str(tmp_path),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["policy"] == "scripted position controller on the planned path"
    assert summary["success"] and summary["contact_steps"] == 0 and summary["steps"] < 600
    assert Path(summary["gif"]).stat().st_size > 0


def test_a_reader_that_stops_early_ends_the_command_quietly():
    """``clutter-gym profiles | head -1``: the pipe closes under the command; no traceback, no hang."""
    cli = Path(sys.executable).with_name("clutter-gym")
    proc = subprocess.Popen([str(cli), "profiles"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, bufsize=0)
    assert proc.stdout.read(10)
    proc.stdout.close()
    _, err = proc.communicate(timeout=60)
    assert b"Traceback" not in err and b"BrokenPipeError" not in err, err.decode()
