#!/usr/bin/env python3
"""Project commands that need nothing but Python and pip: ``python3 tasks.py main|demo|test|bench``.

Each command first makes ``.venv`` (once) and installs clutter-gym into it with its test, training, benchmark and Ray
extras, with torch's version pinned through ``constraints.txt``. The package itself is reinstalled (not in editable
mode) whenever its sources change, so tests always import what a user's ``pip install .`` would give them. ``test``
runs ``ruff check .`` (settings in pyproject.toml) and mypy on the contracts (:data:`TYPED_MODULES`) before pytest.

pybullet 3.2.7 ships wheels for CPython 3.10 and 3.11 only; on a newer Python pip compiles it from source (a C++
compiler, the Python headers and many minutes, see the README). So when ``.venv`` does not exist yet and this file
runs on a newer Python, it makes ``.venv`` with a CPython 3.11 or 3.10 found on PATH instead, and says which.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import venv
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if sys.platform == "win32" else "bin")
PY = BIN / "python"
SOURCES = ("pyproject.toml", "constraints.txt", "envs", "training", "assets")
#: mypy checks these, as installed: the contracts (datatypes.py, interfaces.py), the env core, and the modules that
#: build each env's parts, so every robot, arena, task and sensor an env is made of is held to its protocol.
TYPED_MODULES = ("clutter_gym.datatypes", "clutter_gym.interfaces", "clutter_gym.core",
                 "clutter_gym.clutter_nav", "clutter_gym.clutter_reach", "clutter_gym.clutter_fly",
                 "clutter_gym.collision.checker", "clutter_gym.collision.nearest", "clutter_gym.collision.swept_audit",
                 "clutter_gym.worlds.near_field", "clutter_gym.worlds.pool",
                 "clutter_gym.urdf.checks", "clutter_gym.urdf.geometry", "clutter_gym.urdf.kinematics",
                 "clutter_gym.collision.build", "clutter_gym.builder", "clutter_gym.make_checks",
                 "clutter_gym.robots.omni", "clutter_gym.robots.registry")
#: and these packages, every module in them: the step stages, the dynamics parts, the Sim with its parts, the
#: sensors with their noise models (so a new sensor's two modules are checked with no edit here), and the tasks
#: with their reward terms (a task's Optional state, such as its path field before reset, must be narrowed)
TYPED_PACKAGES = ("clutter_gym.stages", "clutter_gym.dynamics", "clutter_gym.sim", "clutter_gym.sensors",
                  "clutter_gym.noise", "clutter_gym.tasks")
#: The Pythons pybullet 3.2.7 has wheels for, newest first.
WHEEL_PYTHONS = ((3, 11), (3, 10))


def _digest(paths: tuple[str, ...]) -> str:
    h = hashlib.sha256()
    for name in paths:
        path = ROOT / name
        files = (sorted(p for p in path.rglob("*") if p.is_file() and "__pycache__" not in p.parts)
                 if path.is_dir() else [path])
        for f in files:
            h.update(str(f.relative_to(ROOT)).encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def _pip(*args: str) -> None:
    subprocess.run([str(PY), "-m", "pip", "install", "-q", "--disable-pip-version-check", "-c",
                    str(ROOT / "constraints.txt"), *args], check=True)


def wheel_python(version: tuple[int, int], which: Callable[[str], str | None] = shutil.which) -> str | None:
    """A Python with pybullet wheels to make ``.venv`` with when this one (``version``) has none: the path of
    ``python3.11`` or ``python3.10`` on PATH; None when this Python has wheels, or no such Python is found."""
    if version in WHEEL_PYTHONS:
        return None
    for major, minor in WHEEL_PYTHONS:
        found = which(f"python{major}.{minor}")
        if found:
            return found
    return None


def use_a_wheel_python(argv: list[str]) -> None:
    """Before ``.venv`` exists, run this file again under a Python pybullet has wheels for, when this one has none
    (or say what installing on this one costs)."""
    if PY.exists() or os.environ.get("CLUTTER_GYM_TASKS_REEXEC"):
        return
    version = sys.version_info[:2]
    found = wheel_python(version)
    if found:
        print(f"tasks.py: Python {version[0]}.{version[1]} has no pybullet wheel; making .venv with {found}",
              flush=True)
        os.environ["CLUTTER_GYM_TASKS_REEXEC"] = "1"
        os.execv(found, [found, str(Path(__file__).resolve()), *argv])
    if version not in WHEEL_PYTHONS:
        print(f"tasks.py: pybullet 3.2.7 has no wheel for Python {version[0]}.{version[1]} and no python3.11 or "
              "python3.10 is on PATH: pip compiles it from source (needs a C++ compiler and the Python headers; "
              "see the README for the time it takes)", flush=True)


def ensure_installed() -> None:
    """Create .venv and (re)install dependencies and the package when their inputs changed."""
    if not PY.exists():
        print("creating .venv ...", flush=True)
        venv.create(VENV, with_pip=True)
    deps_stamp, pkg_stamp = VENV / ".deps", VENV / ".package"
    deps = _digest(("pyproject.toml", "constraints.txt"))
    if not deps_stamp.exists() or deps_stamp.read_text() != deps:
        print("installing dependencies into .venv (first run: a few minutes) ...", flush=True)
        _pip(f"{ROOT}[test,train,bench,ray]")
        deps_stamp.write_text(deps)
    pkg = _digest(SOURCES)
    if not pkg_stamp.exists() or pkg_stamp.read_text() != pkg:
        shutil.rmtree(ROOT / "build", ignore_errors=True)  # build/lib keeps deleted modules, which would ship
        _pip("--no-deps", "--force-reinstall", str(ROOT))
        pkg_stamp.write_text(pkg)


def static_checks() -> bool:
    """ruff over the repository, then mypy over :data:`TYPED_MODULES` and :data:`TYPED_PACKAGES` (imports followed,
    their errors not shown)."""
    if subprocess.run([str(PY), "-m", "ruff", "check", "."], cwd=ROOT).returncode != 0:
        print("ruff: style errors above (ruff check --fix . fixes import order)", file=sys.stderr)
        return False
    # pybullet and python-fcl ship no type information: their calls are unchecked, not errors
    mypy = [str(PY), "-m", "mypy", "--follow-imports=silent", "--ignore-missing-imports",
            *(arg for m in TYPED_MODULES for arg in ("-m", m)), *(arg for p in TYPED_PACKAGES for arg in ("-p", p))]
    if subprocess.run(mypy, cwd=ROOT).returncode != 0:
        print("mypy: a part no longer has what its protocol in clutter_gym/interfaces.py declares (above)",
              file=sys.stderr)
        return False
    return True


def main(argv: list[str]) -> int:
    commands = {
        "main": [str(BIN / "clutter-gym"), "report"],
        "demo": [str(BIN / "clutter-gym"), "demo"],
        "test": [str(PY), "-m", "pytest"],
        "bench": [str(PY), "-m", "benchmarks.speed_vs_error"],  # run from ROOT, like every command here
    }
    if not argv or argv[0] not in commands:
        print(f"usage: python3 tasks.py {{{'|'.join(commands)}}} [extra arguments]", file=sys.stderr)
        return 2
    use_a_wheel_python(argv)
    ensure_installed()
    if argv[0] == "test" and not static_checks():
        return 1
    return run_to_the_end([*commands[argv[0]], *argv[1:]])


def run_to_the_end(command: list[str]) -> int:
    """Run ``command`` in ROOT and return its exit status (128 + N when signal N ended it, as a shell says).

    Ctrl-C reaches the command too (a terminal signals its whole foreground process group), and the command decides
    what to do with it: the training commands write a checkpoint and exit with 130. So this process waits for it
    to finish instead of killing it, as ``subprocess.run`` would a quarter of a second after the interrupt."""
    process = subprocess.Popen(command, cwd=ROOT)
    while True:
        try:
            status = process.wait()
        except KeyboardInterrupt:
            continue
        return 128 - status if status < 0 else status


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except KeyboardInterrupt:  # while installing or checking: what was installed whole is kept (the stamps)
        print("tasks.py: interrupted", file=sys.stderr)
        sys.exit(130)
