"""A run folder from someone else: its config.yaml may name a robot spec, and its YAML may hold aliases. Neither may
make ``clutter-gym eval`` or ``train --resume`` write or copy anything outside the cache and the run folder, or
take more than bounded memory (docs/training.md, "What a run folder may not do"). Each command runs in a process
of its own, its memory capped."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import pytest
import yaml
from helpers import peak_mib, run_capped

from clutter_gym.assets import asset_path
from clutter_gym.training.commands import env_kwarg
from clutter_gym.training.config import config_for
from clutter_gym.training.run_dir import RUN_FORMAT

#: 475 bytes of aliases of aliases that stand for 9^9 strings
BOMB = ", ".join(['&a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
                 + [f"&a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 9)])
TETRA = "v 0 0 0\nv 0.05 0 0\nv 0 0 0.05\nv 0 0.05 0\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n"
CLI = "import sys\nfrom clutter_gym.cli import main\nsys.exit(main(sys.argv[1:]))\n"


def config_text(**env_kwargs) -> str:
    """A small run's config.yaml, as training writes it, with ``env_kwargs``."""
    config = config_for("ClutterNav-v1", {"timesteps": 128, "n_envs": 1, "checkpoint_every": 64,
                                          "final_eval_episodes": 0, "env_kwargs": {"n_rays": 32, **env_kwargs},
                                          "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1,
                                                  "normalize_obs": False, "normalize_reward": False}})
    return yaml.safe_dump({"run_format": RUN_FORMAT, **config.to_dict()})


def crafted_run(folder: Path, robot: dict) -> Path:
    """A run folder whose config makes ClutterNav-v1 with ``robot`` and holds a (blank) model: enough for eval and
    resume to make the env."""
    (folder / "model").mkdir(parents=True)
    (folder / "model" / "model.zip").write_bytes(b"")
    (folder / "config.yaml").write_text(config_text(robot=robot))
    return folder


def outside_files(root: Path, run: Path, cache: Path) -> list[Path]:
    """Files under ``root`` that the test did not put there and that are neither in the run nor in the cache."""
    return sorted(p for p in root.rglob("*") if p.is_file() and not p.is_relative_to(run)
                  and not p.is_relative_to(cache) and p.name not in ("secret.obj", "v.urdf"))


@pytest.mark.parametrize("command", [["eval", "{run}", "--episodes", "1", "--no-progress"],
                                     ["train", "--resume", "{run}", "--no-progress"]])
@pytest.mark.parametrize("attack", ["name", "mesh"])
def test_a_crafted_run_folder_writes_and_copies_nothing_outside(command, attack, tmp_path):
    """On main a ``name`` that is a path made both commands write ``<name>.urdf`` there, and a mesh naming a file
    outside the URDF's folder was copied into the cache as 0644 (its source 0600); both commands now stop at the
    make with one line naming the field."""
    (tmp_path / "esc").mkdir()
    secret = tmp_path / "private" / "secret.obj"
    secret.parent.mkdir()
    secret.write_text(TETRA)
    secret.chmod(0o600)
    urdf = tmp_path / "robot" / "v.urdf"
    urdf.parent.mkdir()
    deco = (f'<link name="deco"><visual><geometry><mesh filename="file://{secret}"/></geometry></visual></link>'
            '<joint name="dj" type="fixed"><parent link="base_link"/><child link="deco"/></joint></robot>')
    urdf.write_text(asset_path("robots/diffbot.urdf").read_text().replace("</robot>", deco if attack == "mesh"
                                                                          else "</robot>"))
    robot = {"kind": "diff_drive", "urdf": str(urdf), "left_wheels": ["left_wheel_joint"],
             "right_wheels": ["right_wheel_joint"]}
    if attack == "name":
        robot["name"] = f"../../../../../../../..{tmp_path}/esc/evil"
    run, cache = crafted_run(tmp_path / "run", robot), tmp_path / "cache"
    result = run_capped(CLI, *[part.format(run=run) for part in command], timeout=300,
                        env={**os.environ, "XDG_CACHE_HOME": str(cache), "PYTHONWARNINGS": "ignore"})
    assert outside_files(tmp_path, run, cache) == []
    assert not [p for p in cache.rglob("*") if p.name == "secret.obj"]
    lines = [line for line in result.stderr.splitlines() if line.strip() and not line.startswith("peak MiB")]
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-3000:]
    assert lines[0].startswith(f"clutter-gym {command[0]}: error: ")
    assert ("robot: name must be a plain file name" if attack == "name" else "outside the URDF's folder") in lines[0]


def test_a_run_folder_whose_logs_link_out_of_it_is_not_trained_in(tmp_path):
    """On main ``train --resume`` wrote its TensorBoard events through ``tb -> elsewhere`` (and would its
    checkpoints through ``checkpoints -> elsewhere``)."""
    run, elsewhere = tmp_path / "run", tmp_path / "elsewhere"
    run.mkdir()
    elsewhere.mkdir()
    (run / "config.yaml").write_text(config_text())
    (run / "tb").symlink_to(elsewhere)
    result = run_capped(CLI, "train", "--resume", str(run), "--no-progress", timeout=300,
                        env={**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache"), "PYTHONWARNINGS": "ignore"})
    assert list(elsewhere.iterdir()) == []
    assert result.returncode == 2, result.stderr[-3000:]
    assert result.stderr.splitlines()[0] == (f"clutter-gym train: error: {run / 'tb'} is a symbolic link (to "
                                             f"{elsewhere}); training writes there, so a run folder's files must be "
                                             "its own")


def test_a_config_yaml_of_nested_aliases_is_refused_in_bounded_memory(tmp_path):
    """On main ``clutter-gym eval`` of this run reached the 3 GB cap (a MemoryError) expanding the aliases."""
    run = tmp_path / "run"
    run.mkdir()
    config = config_text()
    assert "\nseed: 0\n" in config
    (run / "config.yaml").write_text(config.replace("\nseed: 0\n", f"\nseed: [{BOMB}]\n"))
    result = run_capped(CLI, "eval", str(run), "--episodes", "1", timeout=120,
                        env={**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")})
    assert result.returncode == 2, result.stderr[-3000:]
    assert result.stderr.splitlines()[0] == (
        f"clutter-gym eval: error: {run / 'config.yaml'} stands for more than 1,048,576 nodes and characters with its "
        "aliases expanded (aliases of aliases multiply)")
    assert peak_mib(result) < 1024


def test_a_hyperparameter_file_and_a_sweep_spec_of_nested_aliases_are_refused_in_bounded_memory(tmp_path):
    """On main the aliases were expanded when the settings were checked, or the message printed (a MemoryError)."""
    table = tmp_path / "bomb.yml"
    table.write_text(f"default:\n  seed: [{BOMB}]\n")
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    (sweep / "sweep.yaml").write_text(f"env_id: [{BOMB}]\n")
    code = ("import sys\n"
            "from clutter_gym.training.config import config_for, read_hyperparams_file\n"
            "from clutter_gym.training.sweep import SweepSpec, check_spec\n"
            "for attempt in (lambda: config_for('ClutterNav-v1', read_hyperparams_file(sys.argv[1])),\n"
            "                lambda: check_spec(SweepSpec('ClutterNav-v1', ('none',), ('none',), 1, None, 1),\n"
            "                                   __import__('pathlib').Path(sys.argv[2]))):\n"
            "    try:\n"
            "        attempt()\n"
            "    except ValueError as error:\n"
            "        print(error)\n")
    result = run_capped(code, str(table), str(sweep), timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.splitlines() == [
        f"hyperparameter file {str(table)!r} stands for more than 1,048,576 nodes and characters with its aliases "
        "expanded (aliases of aliases multiply)",
        f"{sweep / 'sweep.yaml'} stands for more than 1,048,576 nodes and characters with its aliases expanded "
        "(aliases of aliases multiply)"]
    assert peak_mib(result) < 1024


def test_an_env_kwarg_of_nested_aliases_is_refused():
    """On main the value was taken, to be expanded by whatever read it next."""
    with pytest.raises(argparse.ArgumentTypeError, match=r"^robot: .* stands for more than 1,048,576 nodes"):
        env_kwarg(f"robot=[{BOMB}]")


def test_a_bad_config_value_is_shown_cut_short():
    """On main the message held the whole value's repr."""
    with pytest.raises(ValueError) as error:
        config_for("ClutterNav-v1", {"seed": list(range(100_000))})
    assert str(error.value) == "seed must be a number in [0, 2147483647], got [0, 1, 2, 3, 4, 5, ...]"
