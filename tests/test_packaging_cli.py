"""The installed package: registration, shipped assets, a wheel that carries them, and the CLI."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import gymnasium as gym
import pytest

import clutter_gym
from clutter_gym.assets import asset_path

REPO = Path(__file__).resolve().parents[1]


def test_import_registers_every_env():
    assert clutter_gym.ENV_IDS
    for env_id in clutter_gym.ENV_IDS:
        assert env_id in gym.registry


def test_assets_resolve_inside_the_imported_package():
    import clutter_gym.assets

    urdf = asset_path("robots/diffbot.urdf")
    assert urdf.is_file() and urdf.is_relative_to(Path(clutter_gym.assets.__file__).parent)


def test_missing_asset_names_the_path():
    with pytest.raises(FileNotFoundError, match="nope.urdf"):
        asset_path("robots/nope.urdf")


def test_wheel_carries_the_assets(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(tmp_path),
         str(REPO)],
        check=True,
    )
    (wheel,) = tmp_path.glob("clutter_gym-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "clutter_gym/assets/robots/diffbot.urdf" in names
    assert "clutter_gym/assets/robots/omnibot.urdf" in names
    assert "clutter_gym/stages/base.py" in names  # every subpackage is listed in pyproject's packages
    assert "clutter_gym/training/baselines.py" in names
    assert "clutter_gym/collision/checker.py" in names
    assert "clutter_gym/noise/profiles.yaml" in names
    assert "clutter_gym/py.typed" in names  # type checkers read the package's hints
    for name in ("ClutterNav-v1", "ClutterNav-v1-student"):  # the shipped agents, whole
        for file in ("card.yaml", "config.yaml", "model/model.zip", "model/vecnormalize.npz"):
            assert f"clutter_gym/training/pretrained/{name}/{file}" in names
    metadata = next(n for n in names if n.endswith(".dist-info/METADATA"))
    assert "License: MIT" in zipfile.ZipFile(wheel).read(metadata).decode()


def test_version_is_the_installed_distribution_version():
    from importlib.metadata import version

    assert clutter_gym.__version__ == version("clutter-gym") != "0+unknown"


def test_demo_cli_writes_a_gif_and_a_clean_summary(tmp_path):
    exe = shutil.which("clutter-gym", path=str(Path(sys.executable).parent))
    assert exe, "the clutter-gym console script is not installed"
    result = subprocess.run(
        [exe, "demo", "--max-steps", "30", "--out", str(tmp_path), "--json", "--noise", "harsh"],
        capture_output=True, text=True, check=True,
    )
    summary = json.loads(result.stdout)  # nothing else on stdout: pybullet's C output is silenced
    assert summary["steps"] == 30 and summary["noise"] == "harsh" and Path(summary["gif"]).stat().st_size > 1000
    assert summary["steps_per_s"] > 0
    assert "b3Warning" not in result.stderr and "pybullet build time" not in result.stderr
    assert list(tmp_path.iterdir()) == [Path(summary["gif"])], "a temporary file was left behind"


def test_demo_cli_rejects_bad_options():
    result = subprocess.run(
        [sys.executable, "-m", "clutter_gym.cli", "demo", "--max-steps", "0"], capture_output=True, text=True
    )
    assert result.returncode == 2 and "must be a positive integer" in result.stderr


def test_profiles_cli_prints_the_table_and_a_profile():
    exe = shutil.which("clutter-gym", path=str(Path(sys.executable).parent))
    table = subprocess.run([exe, "profiles"], capture_output=True, text=True, check=True).stdout
    assert "| `lidar.range_sigma` |" in table and "- `harsh`:" in table
    harsh = json.loads(subprocess.run([exe, "profiles", "harsh"], capture_output=True, text=True, check=True).stdout)
    assert harsh["profile"] == "harsh" and harsh["lidar"]["range_sigma"] == 0.02 and harsh["lidar"]["rate_hz"] == 5.0
