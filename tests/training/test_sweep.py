"""The sim-to-real sweep: a 2x2 grid on a tiny budget fills its CSV and never redoes a finished cell."""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import re
import secrets
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from clutter_gym.training.run_dir import RunDir
from clutter_gym.training.sweep import SweepSpec, cell_dir, run_sweep

SPEC = SweepSpec(env_id="ClutterNav-v1", train_noise=("none", "nominal"), eval_noise=("none", "harsh"), seeds=1,
                 timesteps=64, episodes=1, n_envs=1,
                 settings={"env_kwargs": {"obstacle_density": 0.05, "noise": {"lidar": {"range_sigma": 0.03}}},
                           "ppo": {"n_steps": 64, "batch_size": 32}})


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    return out, run_sweep(SPEC, out, workers=2)


def test_a_2x2_sweep_fills_its_csv_and_heatmap(swept):
    out, result = swept
    assert result["cells_run"] == 2 and result["cells_skipped"] == 0
    with open(out / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {(r["train_noise"], r["eval_noise"]) for r in rows} == {(t, e) for t in SPEC.train_noise
                                                                  for e in SPEC.eval_noise}
    assert all(0.0 <= float(r["success_rate"]) <= 1.0 and r["episodes"] == "1" for r in rows)
    assert (out / "heatmap.png").stat().st_size > 5000
    assert Path(result["summary"]).read_text().startswith("| trained under | evaluated under the same profile |")
    config = RunDir(cell_dir(out, "nominal", 0) / "run").read_config()
    assert config.noise == "nominal" and config.env_kwargs["obstacle_density"] == 0.05
    assert config.make_kwargs("harsh")["noise"] == {"profile": "harsh", "lidar": {"range_sigma": 0.03}}


def test_a_restarted_sweep_skips_finished_cells_and_redoes_only_missing_ones(swept):
    out, _ = swept
    stamps = {p: p.stat().st_mtime_ns for p in out.glob("cells/*/eval-*.json")}
    again = run_sweep(SPEC, out, workers=2)
    assert again["cells_run"] == 0 and again["cells_skipped"] == 2
    assert {p: p.stat().st_mtime_ns for p in out.glob("cells/*/eval-*.json")} == stamps
    (cell_dir(out, "nominal", 0) / "eval-harsh.json").unlink()  # a sweep killed before this evaluation
    model = cell_dir(out, "nominal", 0) / "run" / "model" / "model.zip"
    model_stamp = model.stat().st_mtime_ns
    third = run_sweep(SPEC, out, workers=1)
    assert third["cells_run"] == 1
    assert model.stat().st_mtime_ns == model_stamp, "the finished training must not be redone"


def test_a_sweep_folder_refuses_another_spec(swept):
    out, _ = swept
    with pytest.raises(ValueError, match="another spec"):
        run_sweep(SweepSpec(**{**SPEC.__dict__, "seeds": 2}), out)


def test_the_ray_path_runs_the_same_cells(tmp_path):
    pytest.importorskip("ray")
    spec = SweepSpec(env_id="ClutterNav-v1", train_noise=("none",), eval_noise=("none", "nominal"), seeds=1,
                     timesteps=64, episodes=1, n_envs=1, settings={"ppo": {"n_steps": 64, "batch_size": 32}})
    result = run_sweep(spec, tmp_path, ray_address="local")
    assert result["cells_run"] == 1 and len(result["rows"]) == 2


@pytest.fixture(scope="module")
def ray_cluster():
    """A real two-node Ray cluster (head and one worker, 1 CPU each) on 127.0.0.1, as docs/training.md starts one,
    protected by a token of its own (Ray 2.60 turns token authentication on by itself when ~/.ray holds a token,
    and then a node started without it cannot join). Yields the address and the environment its clients need;
    stops exactly the processes it started (tests/training/ray_cluster.py)."""
    pytest.importorskip("ray")
    if not sys.platform.startswith("linux"):
        pytest.skip("the cluster's launcher reaps Ray's daemons as their subreaper, a Linux feature")
    temp = Path(tempfile.mkdtemp(prefix="cg-ray-", dir="/tmp"))  # short: Ray's socket paths sit under it
    token = temp / "auth_token"
    token.write_text(secrets.token_hex(32))
    env = {**os.environ, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN_PATH": str(token), "RAY_USAGE_STATS_ENABLED": "0"}
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    launcher = subprocess.Popen([sys.executable, str(Path(__file__).with_name("ray_cluster.py")), str(temp), str(port),
                                 "1", "1"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert launcher.stdout.readline().strip() == "ready", "the Ray cluster did not start"
        yield f"127.0.0.1:{port}", env
    finally:
        launcher.stdin.close()
        launcher.wait(timeout=60)
        shutil.rmtree(temp, ignore_errors=True)


def _cli_sweep(out: Path, address: str, env: dict, *extra: str) -> subprocess.CompletedProcess:
    hyperparams = out.parent / f"{out.name}-tiny.yml"
    hyperparams.write_text("default:\n  ppo: {n_steps: 64, batch_size: 32, n_epochs: 1}\n")
    return subprocess.run(
        [str(Path(sys.executable).with_name("clutter-gym")), "sweep", "--env", "ClutterNav-v1", "--train-noise",
         "none,nominal", "--eval-noise", "none", "--seeds", "1", "--timesteps", "64", "--episodes", "1", "--n-envs",
         "2", "--hyperparams", str(hyperparams), "--env-kwargs", "obstacle_density=0.05", "--out", str(out),
         "--ray-address", address, *extra],
        capture_output=True, text=True, env=env, timeout=600)


def test_ray_cluster_of_two_nodes_runs_a_cell_on_each(ray_cluster, tmp_path):
    """Each cell reserves one CPU (the default, not the launching machine's core count): on two 1-CPU nodes, one
    cell runs on each, and a cell steps its envs over the one CPU it reserved."""
    address, env = ray_cluster
    result = _cli_sweep(tmp_path / "sweep", address, env)
    assert result.returncode == 0, result.stderr[-3000:]
    nodes = re.findall(r"cell \S+ done \(ray node (\w+)\)", result.stdout)
    assert len(nodes) == 2 and len(set(nodes)) == 2, result.stdout
    with open(tmp_path / "sweep" / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {(r["train_noise"], r["eval_noise"]) for r in rows} == {("none", "none"), ("nominal", "none")}
    assert (tmp_path / "sweep" / "heatmap.png").stat().st_size > 5000


def test_ray_cluster_refuses_cells_no_node_can_take_at_once(ray_cluster, tmp_path):
    address, env = ray_cluster
    started = time.perf_counter()
    result = _cli_sweep(tmp_path / "sweep", address, env, "--cpus-per-cell", "2")
    assert result.returncode == 2
    assert "each cell asks Ray for 2 CPUs" in result.stderr and "largest node of the cluster" in result.stderr
    assert "Traceback" not in result.stderr
    assert time.perf_counter() - started < 120


def test_the_summary_shows_the_diagonal_and_what_noisy_training_costs_clean():
    """Two seeds: means over seeds, each seed's value in brackets, the clean success lost per seed."""
    from clutter_gym.training.sweep import summary_table

    spec = SweepSpec(env_id="ClutterNav-v1", train_noise=("none", "harsh"), eval_noise=("none", "harsh"), seeds=2,
                     timesteps=64, episodes=100)
    success = {("none", 0, "none"): 0.9, ("none", 1, "none"): 0.8, ("none", 0, "harsh"): 0.5,
               ("none", 1, "harsh"): 0.4, ("harsh", 0, "none"): 0.8, ("harsh", 1, "none"): 0.6,
               ("harsh", 0, "harsh"): 0.7, ("harsh", 1, "harsh"): 0.7}
    rows = [{"train_noise": t, "seed": k, "eval_noise": e, "success_rate": v, "collision_rate": 0.1 * k}
            for (t, k, e), v in success.items()]
    lines = summary_table(rows, spec).splitlines()
    assert lines[2] == ("| `none` | 85% / 5% (90% / 0%, 80% / 10%) | 85% / 5% (90% / 0%, 80% / 10%) "
                        "| +0 points (+0, +0) |")
    assert lines[3] == ("| `harsh` | 70% / 5% (70% / 0%, 70% / 10%) | 70% / 5% (80% / 0%, 60% / 10%) "
                        "| +15 points (+10, +20) |")
    clean_eval_only = SweepSpec(env_id="ClutterNav-v1", train_noise=("none", "harsh"), eval_noise=("harsh",),
                                seeds=2, timesteps=64, episodes=100)
    assert summary_table([r for r in rows if r["eval_noise"] == "harsh"], clean_eval_only).splitlines()[0] == \
        "| trained under | evaluated under the same profile |"


def test_a_sweep_of_students_distils_each_cell_and_evaluates_it_under_every_profile(tmp_path):
    """The sim-to-real sweep takes the teacher -> student route as it takes PPO: each cell's run distils (its
    distill.csv has every round) and is evaluated under each profile from the student's own env arguments."""
    student = {"n_envs": 2, "env_workers": 1, "validate_episodes": 1, "residual_space": "waypoint", "action_bins": 25,
               "teacher": {"name": "planner"}, "distill": {"rounds": 2, "round_steps": 128, "warmup_steps": 32},
               "env_kwargs": {"subgoal_lookahead": 0.0, "reverse": False, "obstacle_density": 0.05}}
    spec = SweepSpec(env_id="ClutterNav-v1", train_noise=("none",), eval_noise=("none", "nominal"), seeds=1,
                     timesteps=300, episodes=1, n_envs=2, settings=student)
    result = run_sweep(spec, tmp_path, workers=1)
    assert result["cells_run"] == 1
    run = RunDir(cell_dir(tmp_path, "none", 0) / "run")
    assert [row["round"] for row in run.read_distill_rows()] == [0.0, 1.0]
    assert run.read_config().teacher.name == "planner" and run.read_config().env_kwargs["subgoal_lookahead"] == 0.0
    with open(tmp_path / "sweep.csv", newline="") as f:
        assert sorted(r["eval_noise"] for r in csv.DictReader(f)) == ["nominal", "none"]


def test_a_mixed_train_profile_trains_a_share_of_the_envs_under_each_profile_and_keeps_the_run_s_own_mix():
    """``none+nominal``: the robust cell. The students' density mix stays; the profiles combine with it."""
    spec = SweepSpec(env_id="ClutterNav-v1", train_noise=("none", "none+low-cost"), eval_noise=("none",), seeds=1,
                     timesteps=64, episodes=1, n_envs=6,
                     settings={"train_env_mix": {"obstacle_density": [0.05, 0.2]}})
    config = spec.cell_config("none+low-cost", 0)
    assert config.noise == "none"
    assert config.train_env_mix == {"obstacle_density": [0.05, 0.2], "noise": ["none", "low-cost"]}
    assert {(config.train_kwargs(i)["obstacle_density"], config.train_kwargs(i)["noise"])
            for i in range(4)} == {(0.05, "none"), (0.05, "low-cost"), (0.2, "none"), (0.2, "low-cost")}
    assert spec.cell_config("none", 0).train_env_mix == {"obstacle_density": [0.05, 0.2]}


@pytest.mark.parametrize("text", ["none+none", "none+loud", "+nominal", "none,,harsh+"])
def test_the_sweep_command_refuses_a_mix_it_cannot_train(text):
    import argparse

    from clutter_gym.training.commands import train_profile_list

    with pytest.raises(argparse.ArgumentTypeError, match="mixes of distinct ones"):
        train_profile_list(text)
    assert train_profile_list("none, none+nominal+low-cost") == ["none", "none+nominal+low-cost"]


def test_a_profile_under_the_reduced_dynamics_trains_or_evaluates_under_it(tmp_path):
    """``none@reduced``: the sim-to-sim gap in the sweep's terms. Trained under the reduced model, the cell's training
    envs take it (its validations keep the run's own, full physics); evaluated under it, the evaluation does. A
    vector env made first starts a forkserver in this process: the sweep's cells, each stepping two envs over worker
    processes, still start theirs (forked cells inherited that forkserver and could not)."""
    import gymnasium as gym

    vector = gym.make_vec("ClutterNav-v1", num_envs=2)
    vector.reset(seed=0)
    vector.close()
    spec = SweepSpec(env_id="ClutterNav-v1", train_noise=("none@reduced", "none+nominal@reduced"),
                     eval_noise=("none", "none@reduced"), seeds=1, timesteps=64, episodes=1, n_envs=2,
                     settings={"env_kwargs": {"obstacle_density": 0.05}, "ppo": {"n_steps": 32, "batch_size": 32}})
    mixed = spec.cell_config("none+nominal@reduced", 0)
    assert mixed.noise == "none" and mixed.train_env_mix == {"noise": ["none", "nominal"], "dynamics": ["reduced"]}
    assert {mixed.train_kwargs(i)["dynamics"] for i in range(2)} == {"reduced"}
    assert "dynamics" not in mixed.env_kwargs
    result = run_sweep(dataclasses.replace(spec, train_noise=("none@reduced",)), tmp_path, workers=1)
    rows = {row["eval_noise"]: row for row in result["rows"]}
    assert set(rows) == {"none", "none@reduced"}
    evaluated = json.loads((cell_dir(tmp_path, "none@reduced", 0) / "eval-none@reduced.json").read_text())
    assert evaluated["env_overrides"] == {"dynamics": "reduced"}


@pytest.mark.parametrize("text", ["none@fast", "loud@reduced", "none+none@reduced"])
def test_the_sweep_command_refuses_a_dynamics_model_it_does_not_know(text):
    import argparse

    from clutter_gym.training.commands import profile_list, train_profile_list

    with pytest.raises(argparse.ArgumentTypeError, match="dynamics model of"):
        train_profile_list(text)
    with pytest.raises(argparse.ArgumentTypeError, match="dynamics model of"):
        profile_list(text)
    assert profile_list("none, nominal@reduced") == ["none", "nominal@reduced"]
