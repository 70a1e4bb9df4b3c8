#!/usr/bin/env python3
"""Project commands that need nothing but Python 3.10+ and pip: ``python3 tasks.py main|demo|test|bench``.

Each command first makes ``.venv`` (once) and installs clutter-gym into it with its test, training, benchmark and Ray
extras, with torch pinned through ``constraints.txt`` (an unpinned torch pulls several GB of CUDA wheels). The package
itself is reinstalled (not in editable mode) whenever its sources change, so tests always import what a user's
``pip install .`` would give them. ``test`` runs ``ruff check .`` (settings in pyproject.toml) before pytest.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if sys.platform == "win32" else "bin")
PY = BIN / "python"
SOURCES = ("pyproject.toml", "constraints.txt", "envs", "training", "assets")


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
        _pip("--no-deps", "--force-reinstall", str(ROOT))
        pkg_stamp.write_text(pkg)


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
    ensure_installed()
    if argv[0] == "test" and subprocess.run([str(PY), "-m", "ruff", "check", "."], cwd=ROOT).returncode != 0:
        print("ruff: style errors above (ruff check --fix . fixes import order)", file=sys.stderr)
        return 1
    return subprocess.run([*commands[argv[0]], *argv[1:]], cwd=ROOT).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
