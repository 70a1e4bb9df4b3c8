"""What is loaded from a run folder is checked against the run's config.yaml and its env's observation space first:
the normalisation statistics (``vecnormalize.npz``) member by member, before their arrays are read, and the
weights in ``model.zip``. Each case is a file someone could hand over; each is refused in one line naming the file
and the member or setting, by ``eval``, by ``load`` and by ``train --resume``."""

from __future__ import annotations

import io
import json
import pickle
import shutil
import subprocess
import sys
import textwrap
import zipfile

import numpy as np
import pytest
import torch
from helpers import Touch, copy_run

from clutter_gym.cli import main
from clutter_gym.training import load, policy_file
from clutter_gym.training.config import config_for
from clutter_gym.training.normalizer import NORMALIZER_FILE
from clutter_gym.training.run_dir import MODEL_FILE
from clutter_gym.training.train import start, train

#: a run of two checkpoints (steps 64 and 128) and a final model, on 32 LIDAR rays
SMALL = {"timesteps": 128, "n_envs": 1, "checkpoint_every": 64, "final_eval_episodes": 0,
         "env_kwargs": {"obstacle_density": 0.05, "n_rays": 32},
         "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1}}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    run = start(config_for("ClutterNav-v1", SMALL), tmp_path_factory.mktemp("statistics") / "run")
    train(run, progress=False)
    return run


def _rewrite(path, changes: dict) -> None:
    """``path`` (a vecnormalize.npz) with members (``obs/lidar/mean``) or settings (``settings.clip_obs``)
    replaced."""
    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files}
    settings = json.loads(str(arrays["settings"]))
    for name, value in changes.items():
        if name.startswith("settings."):
            settings[name.removeprefix("settings.")] = value
            arrays["settings"] = np.array(json.dumps(settings))
        else:
            arrays[name] = value
    with path.open("wb") as f:
        np.savez(f, **arrays)


def _one_line_error(argv: list[str], capsys) -> str:
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


LIDAR = 32  # entries of obs/lidar in the SMALL run
STATISTICS = {
    "a (1,)-shaped mean, which broadcast": (
        {"obs/lidar/mean": np.zeros(1)}, "obs/lidar/mean is an array of shape (1,) and dtype float64; expected "
                                         f"shape ({LIDAR},)"),
    "an infinite variance": ({"obs/lidar/var": np.full(LIDAR, np.inf)}, "obs/lidar/var must hold finite floats"),
    "a negative variance": ({"obs/lidar/var": np.full(LIDAR, -1.0)}, "obs/lidar/var must not be negative"),
    "a NaN mean": ({"obs/goal/mean": np.full(3, np.nan)}, "obs/goal/mean must hold finite floats"),
    "strings": ({"obs/lidar/mean": np.array(["x"] * LIDAR)}, "obs/lidar/mean must hold finite floats"),
    "a zero count": ({"ret/count": np.array(0.0)}, "ret/count must be above 0"),
    "a member too many": ({"obs/extra/mean": np.zeros(2)}, "unexpected ['obs/extra/mean']"),
    "clip_obs -1": ({"settings.clip_obs": -1}, "settings.clip_obs is -1, but training writes 10.0"),
    "norm_obs false in a run trained normalised": (
        {"settings.norm_obs": False}, "settings.norm_obs is false, but config.yaml says ppo.normalize_obs: true"),
    "norm_obs 1, not true": ({"settings.norm_obs": 1}, "settings.norm_obs is 1, but config.yaml says"),
    "another gamma": ({"settings.gamma": 0.5}, "settings.gamma is 0.5, but config.yaml says ppo.gamma: 0.99"),
    "fewer keys normalised": ({"settings.norm_obs_keys": ["lidar"]}, "settings.norm_obs_keys is [\"lidar\"], but"),
    "settings that are not a mapping": ({"settings": np.array("[1, 2]")}, "settings must have the keys"),
}


@pytest.mark.parametrize("changes, message", STATISTICS.values(), ids=STATISTICS.keys())
def test_statistics_that_are_not_the_runs_are_refused_naming_file_and_field(finished, tmp_path, capsys, changes,
                                                                          message):
    """Before, the (1,)-shaped mean, the infinite variance, clip_obs -1, norm_obs false and the other settings
    loaded and evaluated with exit 0: the policy acted on observations it was never trained on."""
    run = copy_run(finished, tmp_path)
    path = run.model_dir / NORMALIZER_FILE
    _rewrite(path, changes)
    line = _one_line_error(["eval", str(run.root), "--episodes", "1"], capsys)
    assert f"{path}: " in line and message in line, line
    with pytest.raises(ValueError, match="^" + str(path)):
        load(run.root)


@pytest.mark.parametrize("bad", [np.full(LIDAR, np.nan), np.array(["x"] * LIDAR)], ids=["NaN", "strings"])
def test_resume_from_bad_statistics_names_them_and_goes_back_a_checkpoint(finished, tmp_path, capsys, bad):
    """NaN or string statistics in the newest checkpoint gave raw tracebacks on --resume."""
    run = copy_run(finished, tmp_path)
    shutil.rmtree(run.model_dir)  # a run killed before its end: it resumes from its newest checkpoint
    (older, _), (newest_step, newest) = run.checkpoints()
    _rewrite(newest / NORMALIZER_FILE, {"obs/lidar/mean": bad})
    assert main(["train", "--resume", str(run.root), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"{newest} cannot be continued from ({newest / NORMALIZER_FILE}: obs/lidar/mean must hold finite " in err
    assert "removed, trying the one before it" in err
    assert load(run.root).step == newest_step and older < newest_step


def _replace_member(path, name: str, content: bytes) -> None:
    with zipfile.ZipFile(path) as archive:
        entries = {entry: archive.read(entry) for entry in archive.namelist()}
    entries[name] = content
    with zipfile.ZipFile(path, "w") as archive:
        for entry, data in entries.items():
            archive.writestr(entry, data)


def test_a_pickle_in_the_optimizer_weights_is_named_in_one_line(finished, tmp_path, capsys):
    """A pickle in policy.optimizer.pth gave a raw UnpicklingError (torch's text, which suggests loading it without
    the guard); no code ran, and none runs now."""
    run = copy_run(finished, tmp_path)
    marker = tmp_path / "pwned"
    for folder in (run.model_dir, run.checkpoints()[-1][1]):
        _replace_member(folder / MODEL_FILE, "policy.optimizer.pth", pickle.dumps(Touch(marker)))
    line = _one_line_error(["eval", str(run.root), "--episodes", "1"], capsys)
    assert f"{run.model_dir / MODEL_FILE} is not a complete SB3 model file" in line
    assert "policy.optimizer.pth is not plain weights: torch's weights-only loader refused it" in line
    assert "weights_only" not in line  # torch's advice to load it unguarded is not passed on
    shutil.rmtree(run.model_dir)
    assert main(["train", "--resume", str(run.root), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "policy.optimizer.pth is not plain weights" in err
    assert not marker.exists()


def test_non_finite_weights_and_oversized_members_are_named(finished, tmp_path, capsys, monkeypatch):
    run = copy_run(finished, tmp_path)
    path = run.model_dir / MODEL_FILE
    with zipfile.ZipFile(path) as archive:
        weights = torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True)
    next(iter(weights.values())).fill_(float("nan"))
    buffer = io.BytesIO()
    torch.save(weights, buffer)
    _replace_member(path, "policy.pth", buffer.getvalue())
    line = _one_line_error(["eval", str(run.root), "--episodes", "1"], capsys)
    assert "policy.pth holds a tensor with NaN or infinite values" in line
    monkeypatch.setattr(policy_file, "MAX_WEIGHTS_BYTES", 1000)
    with pytest.raises(ValueError, match=r"\.pth holds [\d,]+ bytes, at most 1,000 allowed"):
        policy_file.read_attributes(finished.model_dir / MODEL_FILE)


def test_weights_of_another_shape_are_one_line(finished, tmp_path, capsys):
    """A model.zip of another network (here 16 LIDAR rays where the config says 32) gave torch's many-line size
    mismatch."""
    other = start(config_for("ClutterNav-v1", {**SMALL, "timesteps": 64, "env_kwargs": {"obstacle_density": 0.05,
                                                                                        "n_rays": 16}}),
                  tmp_path / "other")
    train(other, progress=False)
    run = copy_run(finished, tmp_path)
    shutil.copy(other.model_dir / MODEL_FILE, run.model_dir / MODEL_FILE)
    line = _one_line_error(["eval", str(run.root), "--episodes", "1"], capsys)
    assert f"{run.model_dir / MODEL_FILE} does not fit the policy of this run's config.yaml" in line


def test_a_member_declaring_a_huge_array_is_refused_before_it_is_read(finished, tmp_path):
    """A 0.8 MB deflated member declaring 100 million floats (800 MB) was read whole: the issue's (400,000,000,)
    took eval past 2.6 GB. Its header is read first now, and load() allocates no more than it does on any run."""
    run = copy_run(finished, tmp_path)
    path = run.model_dir / NORMALIZER_FILE
    with zipfile.ZipFile(path) as archive:
        entries = {entry: archive.read(entry) for entry in archive.namelist()}
    count = 100_000_000
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (count,)})
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for entry, data in entries.items():
            if entry != "obs/lidar/mean.npy":
                archive.writestr(entry, data)
        with archive.open("obs/lidar/mean.npy", "w") as member:
            member.write(header.getvalue())
            zeros = bytes(1 << 23)
            for _ in range(count * 8 // len(zeros)):
                member.write(zeros)
    assert path.stat().st_size < 1_000_000
    script = textwrap.dedent(f"""
        import tracemalloc
        from clutter_gym.training import load
        tracemalloc.start()  # numpy's arrays are traced; the process's own peak would count numba's compiling too
        try:
            load({str(run.root)!r})
        except ValueError as error:
            print(error)
        print(tracemalloc.get_traced_memory()[1])
        """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    message, peak = done.stdout.splitlines()[-2:]
    assert message.startswith(f"{path}: obs/lidar/mean is an array of shape ({count},)"), message
    assert int(peak) < 1 << 28, f"load() allocated {int(peak) / 2**20:.0f} MiB at its peak"


def test_a_crafted_pickle_in_the_statistics_member_list_runs_nothing(finished, tmp_path):
    """An object array (a pickle inside the .npy) is refused by its header's dtype, not by unpickling it."""
    run = copy_run(finished, tmp_path)
    path = run.model_dir / NORMALIZER_FILE
    marker = tmp_path / "pwned"
    payload = np.empty(LIDAR, dtype=object)
    payload[0] = Touch(marker)
    buffer = io.BytesIO()
    np.save(buffer, payload, allow_pickle=True)
    _replace_member(path, "obs/lidar/mean.npy", buffer.getvalue())
    with pytest.raises(ValueError, match=r"obs/lidar/mean is an array of shape \(32,\) and dtype object"):
        load(run.root)
    assert not marker.exists()
