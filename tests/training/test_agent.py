"""``clutter_gym.training.load``: a run folder back as an agent that acts on plain env observations."""

from __future__ import annotations

import shutil
import stat

import numpy as np
import pytest
import yaml

from clutter_gym.training import Agent, load
from clutter_gym.training.config import config_for
from clutter_gym.training.normalizer import NORMALIZER_FILE
from clutter_gym.training.run_dir import MODEL_FILE, RUN_FORMAT, IncompatibleRunError
from clutter_gym.training.train import start, train

TINY = {"timesteps": 128, "n_envs": 1, "checkpoint_every": 64, "final_eval_episodes": 0,
        "env_kwargs": {"obstacle_density": 0.05, "n_rays": 32}, "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1}}


@pytest.fixture(scope="module", params=[True, False], ids=["normalized", "raw"])
def run(request, tmp_path_factory):
    """A finished tiny run with and without observation normalisation (the wrappers a run can hold today)."""
    config = config_for("ClutterNav-v1", {**TINY, "ppo": {**TINY["ppo"], "normalize_obs": request.param}})
    run = start(config, tmp_path_factory.mktemp("agent") / "run")
    train(run, progress=False)
    return run


def test_predict_applies_the_observation_normalisation_the_run_trained_with(run):
    agent = load(run.root)
    assert isinstance(agent, Agent) and agent.step == 128 and agent.config == run.read_config()
    env = agent.make_env()
    obs, _ = env.reset(seed=4)
    env.close()
    action, state = agent.predict(obs)
    assert action.shape == (2,) and state is None
    expected_input = obs
    if run.read_config().ppo.normalize_obs:  # SB3's formula, from the saved arrays
        with np.load(run.model_dir / NORMALIZER_FILE) as stats:
            expected_input = {key: np.clip((value - stats[f"obs/{key}/mean"]) / np.sqrt(stats[f"obs/{key}/var"] + 1e-8),
                                           -10.0, 10.0).astype(np.float32) for key, value in obs.items()}
        assert not np.allclose(expected_input["lidar"], obs["lidar"])  # normalisation changes what the network sees
    expected, _ = agent.model.predict(expected_input, deterministic=True)
    np.testing.assert_array_equal(action, expected)


def test_predict_takes_a_batch_and_checks_its_input(run):
    agent = load(run.root)
    env = agent.make_env()
    obs, _ = env.reset(seed=1)
    env.close()
    batch = {k: np.stack([v, v]) for k, v in obs.items()}
    actions, _ = agent.predict(batch)
    single, _ = agent.predict(obs)
    assert actions.shape == (2, 2)
    np.testing.assert_allclose(actions[0], single, atol=1e-6)
    with pytest.raises(ValueError, match=r"keys \['goal', 'lidar', 'subgoal', 'velocity'\]"):
        agent.predict({"lidar": obs["lidar"]})
    with pytest.raises(ValueError, match=r"obs\['lidar'\] must have shape \(32,\)"):
        agent.predict({**obs, "lidar": np.zeros(64, np.float32)})


def test_make_env_rebuilds_the_run_env_with_overrides(run):
    agent = load(run.root)
    env = agent.make_env()
    assert env.unwrapped.spec.kwargs["obstacle_density"] == 0.05 and env.observation_space["lidar"].shape == (32,)
    env.close()
    env = agent.make_env(noise="harsh", obstacle_density=0.2)
    assert env.unwrapped.spec.kwargs["obstacle_density"] == 0.2 and env.unwrapped.spec.kwargs["noise"] == "harsh"
    env.close()
    with pytest.raises(ValueError, match=r"observations of shape .*'lidar': \(64,\).* trained on .*'lidar': \(32,\)"):
        agent.make_env(n_rays=64)
    with pytest.raises(ValueError, match=r"unknown env_kwargs key\(s\) for ClutterNav-v1 \['bogus'\]; allowed: \["):
        agent.make_env(bogus=1)
    with pytest.raises(ValueError, match="noise must be one of"):
        agent.make_env(noise="loud")


def test_load_picks_a_checkpoint_by_step_and_lists_the_ones_there_are(run):
    assert load(run.root, step=64).step == 64
    with pytest.raises(FileNotFoundError, match=r"no checkpoint of step 65; it has \[64, 128\]"):
        load(run.root, step=65)
    with pytest.raises(FileNotFoundError, match="no config.yaml"):
        load(run.root / "missing")


def test_the_run_folder_records_its_format_and_the_versions_that_wrote_it(run):
    saved = yaml.safe_load(run.config_file.read_text())
    assert saved["run_format"] == RUN_FORMAT
    assert {"clutter-gym", "stable-baselines3", "torch", "gymnasium", "python"} <= saved["written_by"].keys()


def _copy(run, tmp_path):
    shutil.copytree(run.root, tmp_path / "copy")
    return tmp_path / "copy"


def test_runs_this_version_cannot_rebuild_give_a_clear_error(run, tmp_path):
    copy = _copy(run, tmp_path)
    config = copy / "config.yaml"
    data = yaml.safe_load(config.read_text())
    config.write_text(yaml.safe_dump({**data, "run_format": RUN_FORMAT + 1}))
    with pytest.raises(IncompatibleRunError, match=f"format {RUN_FORMAT + 1}.*use the version that wrote it"):
        load(copy)
    config.write_text(yaml.safe_dump({**data, "curriculum": {"stages": 3}}))
    with pytest.raises(IncompatibleRunError,
                       match=r"does not fit clutter-gym .*unknown config key\(s\) \['curriculum'\]"):
        load(copy)
    config.write_text(yaml.safe_dump(data))
    (copy / "model" / MODEL_FILE).write_bytes(b"PK\x03\x04 not a model")
    with pytest.raises(IncompatibleRunError, match=r"cannot be loaded .*written by clutter-gym \d"):
        load(copy)


def test_a_run_written_before_formats_were_recorded_still_loads(run, tmp_path):
    copy = _copy(run, tmp_path)
    data = yaml.safe_load((copy / "config.yaml").read_text())
    del data["run_format"], data["written_by"]
    (copy / "config.yaml").write_text(yaml.safe_dump(data))
    assert load(copy).step == 128


def test_a_run_folder_is_readable_by_other_users_under_umask_022(tmp_path):
    import os

    old = os.umask(0o022)
    try:
        config = config_for("ClutterNav-v1", {**TINY, "timesteps": 64, "checkpoint_every": 64})
        run = start(config, tmp_path / "run")
        train(run, progress=False)
    finally:
        os.umask(old)
    modes = {p: stat.S_IMODE(p.stat().st_mode) for p in run.root.rglob("*")}
    assert any(p.name == MODEL_FILE for p in modes)
    assert {p.name: m for p, m in modes.items() if m & 0o044 != 0o044} == {}
    assert {p.name: m for p, m in modes.items() if p.is_dir() and m & 0o055 != 0o055} == {}


def test_make_env_takes_noise_overrides_on_top_of_the_runs(tmp_path):
    config = config_for("ClutterNav-v1", {**TINY, "timesteps": 64, "checkpoint_every": 64,
                                          "env_kwargs": {"noise": {"lidar": {"range_sigma": 0.03}}}})
    run = start(config, tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    env = agent.make_env(noise={"profile": "harsh", "imu": {"latency_steps": 0}})
    assert env.unwrapped.spec.kwargs["noise"] == {"profile": "harsh", "lidar": {"range_sigma": 0.03},
                                                  "imu": {"latency_steps": 0}}
    env.close()
    env = agent.make_env()
    assert env.unwrapped.spec.kwargs["noise"] == {"profile": "none", "lidar": {"range_sigma": 0.03}}
    env.close()


def test_the_run_folder_records_the_commit_of_the_checkout_it_was_started_from(tmp_path):
    import subprocess
    from pathlib import Path

    from clutter_gym.training.run_dir import checkout_commit

    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        pytest.skip("the tests do not run from a git checkout")
    head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                          check=True).stdout.strip()
    assert checkout_commit(root / "training").removesuffix("-dirty") == head
    assert checkout_commit(tmp_path) is None  # not a checkout (of clutter-gym)
