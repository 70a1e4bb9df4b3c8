"""A bare ``pip install .`` (no ``[train]`` extra): the envs, the scripted baselines and every command that does not
train work; the training commands say in one line which extra to install.

The venv is built once per session: the package's wheel (built here, without build isolation, as
test_packaging_cli does) installed with its dependencies by this interpreter's pip into a venv that has no pip of its
own and does not see this one's site packages, so stable-baselines3 and torch are absent as in a user's bare
install. ``--no-compile`` skips byte-compiling the dependencies (most of the install's time), and pip's cache keeps
the second build from downloading (about 150 MB of wheels the first time). With a warm cache the venv took 26 s and
the whole module 2 min 10 s on the 2-core machine at a load average of 6 (other people's training); most of it is
the commands importing the envs in fresh processes. Slower than most tests, but not marked slow: only the default
suite would catch a training import that creeps into the envs or the command line.
"""

from __future__ import annotations

import json
import subprocess
import sys
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
EXTRA = "pip install 'clutter-gym[train]'"


@pytest.fixture(scope="module")
def bare(tmp_path_factory) -> Path:
    """The bin folder of a venv holding only ``pip install .``."""
    root = tmp_path_factory.mktemp("bare")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(root / "wheel"), str(REPO)], check=True)
    (wheel,) = (root / "wheel").glob("clutter_gym-*.whl")
    venv.create(root / "venv", with_pip=False)
    bin_dir = root / "venv" / "bin"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(bin_dir / "python"), "install", "-q",
                    "--no-compile", "--disable-pip-version-check", "-c", str(REPO / "constraints.txt"), str(wheel)],
                   check=True)
    absent = subprocess.run([bin_dir / "python", "-c", "import stable_baselines3"], capture_output=True)
    assert absent.returncode != 0, "the bare venv sees stable-baselines3: the test would prove nothing"
    return bin_dir


def _run(bare: Path, *args: str, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=300, **kwargs)


@pytest.mark.parametrize("args", [["--help"], ["profiles"], ["train", "--help"]])
def test_commands_that_do_not_train_work(bare, args):
    result = _run(bare, bare / "clutter-gym", *args)
    assert result.returncode == 0 and "Traceback" not in result.stderr, result.stderr
    assert result.stdout


def test_the_demo_runs(bare, tmp_path):
    result = _run(bare, bare / "clutter-gym", "demo", "--max-steps", "5", "--frame-every", "5", "--out", tmp_path,
                  "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["steps"] == 5


def test_the_envs_and_the_scripted_baselines_import_and_make(bare):
    code = ("import gymnasium as gym, clutter_gym\n"
            "from clutter_gym.training.baselines import PotentialFieldNavigator\n"
            "from clutter_gym.training.joint_planner import JointPlannerReacher\n"
            "env = gym.make('ClutterNavTrain-v1')\n"
            "obs, _ = env.reset(seed=0)\n"
            "env.step(PotentialFieldNavigator.for_env(env)(obs))\n"
            "env.close()\n")
    result = _run(bare, bare / "python", "-c", code)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("args", [["train", "--timesteps", "64"], ["eval", "runs/x"], ["sweep"], ["report"],
                                  ["demo", "--agent", "pretrained/ClutterNav-v1"]])
def test_training_commands_name_the_extra_in_one_line(bare, tmp_path, args):
    result = _run(bare, bare / "clutter-gym", *args, cwd=tmp_path)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 1 and len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert lines[0].startswith(f"clutter-gym {args[0]}: error: ") and EXTRA in lines[0]
    assert not list(tmp_path.iterdir()), "a command that cannot run left files behind"


def test_load_raises_gymnasiums_dependency_error(bare):
    result = _run(bare, bare / "python", "-c", "from clutter_gym.training import load")
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("gymnasium.error.DependencyNotInstalled: ") and EXTRA in last, result.stderr
