"""Env versions as CHANGELOG.md promises: the ids whose results at defaults changed gained -v1, the old ids name
the new ones, each env's page has a version history, and a run trained on an old id still loads."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import pytest
import tomllib

import clutter_gym
from clutter_gym import ENV_IDS, RENAMED_IDS

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("old_id", sorted(RENAMED_IDS))
def test_an_old_id_is_refused_with_the_new_one_named(old_id):
    with pytest.raises(gym.error.DeprecatedEnv, match=re.escape(RENAMED_IDS[old_id])):
        gym.make(old_id)


def test_every_env_id_is_registered_at_its_current_version():
    assert set(RENAMED_IDS.values()) == set(ENV_IDS)
    for env_id in (*ENV_IDS, "ClutterReachGoal-v1", *clutter_gym.TRAIN_IDS):
        assert env_id in gym.registry


def test_the_changelog_has_the_packaged_version_and_every_env_page_a_version_history():
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert re.search(rf"^## {re.escape(version)} \(\d{{4}}-\d\d-\d\d\)$", (ROOT / "CHANGELOG.md").read_text(), re.M)
    for env_id in ENV_IDS:  # each env's page, generated from its docstring, opens its history at its id's version
        page = (ROOT / "docs" / "envs" / f"{env_id}.md").read_text()
        newest = env_id.rsplit("-", 1)[1]
        assert f"## Version history\n\n* {newest} (clutter-gym 0.3.0)" in page, env_id


def test_a_run_trained_on_an_old_id_is_read_as_the_new_one_with_a_warning(tmp_path):
    from clutter_gym.training.config import config_for
    from clutter_gym.training.run_dir import RunDir
    from clutter_gym.training.train import start

    run = start(config_for("ClutterNav-v1"), tmp_path / "run")
    text = run.config_file.read_text()
    run.config_file.write_text(text.replace("env_id: ClutterNav-v1", "env_id: ClutterNav-v0"))
    with pytest.warns(UserWarning, match="trained on ClutterNav-v0.*read as ClutterNav-v1"):
        config = RunDir(run.root).read_config()
    assert config.env_id == "ClutterNav-v1"
