"""The sim-to-real sweep: a 2x2 grid on a tiny budget fills its CSV and never redoes a finished cell."""

from __future__ import annotations

import csv

import pytest

from clutter_gym.training.run_dir import RunDir
from clutter_gym.training.sweep import SweepSpec, cell_dir, run_sweep

SPEC = SweepSpec(env_id="ClutterNav-v0", train_noise=("none", "nominal"), eval_noise=("none", "harsh"), seeds=1,
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
    spec = SweepSpec(env_id="ClutterNav-v0", train_noise=("none",), eval_noise=("none", "nominal"), seeds=1,
                     timesteps=64, episodes=1, n_envs=1, settings={"ppo": {"n_steps": 64, "batch_size": 32}})
    result = run_sweep(spec, tmp_path, ray_address="local")
    assert result["cells_run"] == 1 and len(result["rows"]) == 2
