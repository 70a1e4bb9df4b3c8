"""Run folders that are safe to load and to resume: nothing in them runs code, nothing missing goes unnoticed, and a
run killed or starved at any point resumes from what is complete, saying what it does."""

from __future__ import annotations

import base64
import json
import os
import pickle
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from helpers import Touch as _Touch
from helpers import copy_run as _copy  # the names this file's tests use

from clutter_gym.cli import main
from clutter_gym.training import load
from clutter_gym.training.config import config_for
from clutter_gym.training.normalizer import LEGACY_NORMALIZER_FILE, NORMALIZER_FILE, UntrustedFileError, wrap
from clutter_gym.training.run_dir import MODEL_FILE, RunDir
from clutter_gym.training.train import start, train

TINY = {"timesteps": 768, "n_envs": 1, "checkpoint_every": 384, "final_eval_episodes": 0,
        "env_kwargs": {"obstacle_density": 0.05, "n_rays": 32}, "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1}}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    run = start(config_for("ClutterNav-v1", TINY), tmp_path_factory.mktemp("safety") / "run")
    train(run, progress=False)
    return run


def _eval(run: RunDir, *extra: str) -> list[str]:
    return ["eval", str(run.root), "--episodes", "1", *extra]


def test_the_run_folder_holds_no_pickle_and_the_statistics_are_plain_arrays(finished):
    assert not list(finished.root.rglob("*.pkl"))
    with np.load(finished.model_dir / NORMALIZER_FILE, allow_pickle=False) as data:
        assert {"settings", "ret/mean", "obs/lidar/mean", "obs/lidar/var", "obs/lidar/count"} <= set(data.files)


def test_a_crafted_normalizer_pickle_is_not_loaded_without_trust(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    marker = tmp_path / "pwned"
    (run.model_dir / NORMALIZER_FILE).unlink()
    (run.model_dir / LEGACY_NORMALIZER_FILE).write_bytes(pickle.dumps(_Touch(marker)))
    with pytest.raises(SystemExit) as exit_:
        main(_eval(run))
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert f"{run.model_dir / LEGACY_NORMALIZER_FILE} is a pickle" in err and "--trust-pickle" in err
    with pytest.raises(UntrustedFileError):
        load(run.root)
    with pytest.raises(UntrustedFileError):
        train(run, progress=False, timesteps=1024)
    assert not marker.exists()


def test_a_crafted_model_zip_runs_no_code_on_load(finished, tmp_path):
    """Every attribute SB3 pickled into the zip is replaced, so a payload in any of them (or a new one) is never
    unpickled."""
    run = _copy(finished, tmp_path)
    marker = tmp_path / "pwned"
    path = run.model_dir / MODEL_FILE
    with zipfile.ZipFile(path) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    data = json.loads(entries["data"])
    payload = {":type:": "<class 'x'>", ":serialized:": base64.b64encode(pickle.dumps(_Touch(marker))).decode()}
    pickled = [key for key, item in data.items() if isinstance(item, dict) and ":serialized:" in item]
    assert {"policy_class", "observation_space", "action_space", "lr_schedule", "clip_range"} <= set(pickled)
    entries["data"] = json.dumps({**data, **dict.fromkeys(pickled, payload), "extra": payload}).encode()
    with zipfile.ZipFile(path, "w") as archive:
        for name, content in entries.items():
            archive.writestr(name, content)
    agent = load(run.root)
    assert not marker.exists()
    env = agent.make_env()
    obs, _ = env.reset(seed=0)
    env.close()
    np.testing.assert_array_equal(agent.predict(obs)[0], load(finished.root).predict(obs)[0])


def test_an_older_run_loads_with_trust_pickle_and_acts_the_same(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    config = run.read_config()
    from stable_baselines3.common.vec_env import DummyVecEnv

    from clutter_gym.training.vec_env import make_env

    # what clutter-gym 0.1 wrote: SB3's own pickle of the same statistics
    legacy = wrap(DummyVecEnv([lambda: make_env(config.env_id, config.make_kwargs())]), run.model_dir / NORMALIZER_FILE,
                  config)
    legacy.save(str(run.model_dir / LEGACY_NORMALIZER_FILE))
    legacy.close()
    (run.model_dir / NORMALIZER_FILE).unlink()
    assert main(_eval(run, "--trust-pickle", "--json")) == 0
    trusted = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert (run.model_dir / NORMALIZER_FILE).is_file()  # rewritten: the next load needs no trust
    assert main(_eval(finished, "--json")) == 0
    original = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert trusted["per_episode"] == original["per_episode"]


def test_missing_statistics_refuse_to_load_or_resume(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    (run.model_dir / NORMALIZER_FILE).unlink()
    with pytest.raises(SystemExit) as exit_:
        main(_eval(run))
    assert exit_.value.code == 2
    assert f"{run.model_dir / NORMALIZER_FILE} is missing" in capsys.readouterr().err
    for _, folder in run.checkpoints():
        (folder / NORMALIZER_FILE).unlink()
    with pytest.raises(FileNotFoundError, match="vecnormalize.npz is missing"):
        train(run, progress=False, timesteps=1024)


def test_resume_of_a_finished_run_is_a_no_op_that_says_so(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    before = {p: p.stat().st_mtime_ns for p in run.root.rglob("*") if p.is_file()}
    assert main(["train", "--resume", str(run.root), "--no-progress"]) == 0
    assert "finished training at step 768: nothing to resume" in capsys.readouterr().err
    assert {p: p.stat().st_mtime_ns for p in run.root.rglob("*") if p.is_file()} == before


def test_a_run_killed_before_its_first_checkpoint_starts_over_and_keeps_one_attempts_rows(tmp_path, capsys):
    run = start(config_for("ClutterNav-v1", {**TINY, "timesteps": 1024, "checkpoint_every": 2048}), tmp_path / "run")
    train(run, progress=False)
    first_attempt = run.read_episodes()
    assert first_attempt and not run.checkpoints()
    shutil.rmtree(run.model_dir)  # killed just before the end: no checkpoint, no final model, the rows logged
    train(run, progress=False)
    assert f"starting over from step 0 (dropped the {len(first_attempt)} episode rows" in capsys.readouterr().err
    assert run.read_episodes() == first_attempt  # the same seeds again, logged once


def test_a_torn_last_episode_row_is_dropped_on_resume(finished, tmp_path):
    run = _copy(finished, tmp_path)
    shutil.rmtree(run.model_dir)
    rows = run.read_episodes()
    assert rows
    with run.episodes_file.open("a") as f:
        f.write("700.0,1.0,0")  # killed mid-row: no line end
    assert run.read_episodes() == rows
    train(run, progress=False)
    steps = [row["timestep"] for row in run.read_episodes()]
    assert steps == sorted(steps) and load(run.root).step == 768


def test_a_corrupt_newest_checkpoint_falls_back_to_the_one_before(finished, tmp_path, capsys):
    run = _copy(finished, tmp_path)
    shutil.rmtree(run.model_dir)
    newest = run.latest_checkpoint()[1] / MODEL_FILE
    newest.write_bytes(newest.read_bytes()[: newest.stat().st_size // 2])  # a truncated write
    train(run, progress=False)
    err = capsys.readouterr().err
    assert f"{newest.parent} cannot be continued from" in err and "trying the one before it" in err
    assert load(run.root).step == 768


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_FSIZE and SIGXFSZ")
def test_a_checkpoint_that_cannot_be_written_is_one_line_naming_the_folder(tmp_path):
    """A file size limit makes every write past it fail in the kernel, as a full disk does (EFBIG instead of
    ENOSPC), without root or a small file system: the model file cannot be written, everything smaller can."""
    script = (
        "import resource, signal, sys\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (40_000, 40_000))\n"
        "from clutter_gym.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    out = tmp_path / "run"
    result = subprocess.run(
        [sys.executable, "-c", script, "train", "--out", str(out), "--timesteps", "128", "--n-envs", "1",
         "--checkpoint-every", "64", "--final-eval-episodes", "0", "--n-steps", "64", "--batch-size", "32",
         "--n-epochs", "1", "--no-progress", "--env-kwargs", "obstacle_density=0.05", "n_rays=32"],
        capture_output=True, text=True, timeout=300, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert result.returncode == 2, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert lines[0].startswith("clutter-gym train: error: could not write ")
    assert "checkpoints" in lines[0] and "MiB free there" in lines[0]
    assert not list((out / "checkpoints").glob("step_*")) if (out / "checkpoints").exists() else True
