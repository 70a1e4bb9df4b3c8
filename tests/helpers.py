"""Plain helpers shared by test modules in several folders: ``from helpers import empty_scene``.

Importable because pyproject.toml puts ``tests`` on pytest's ``pythonpath``. Fixtures live in conftest.py instead,
which pytest loads by itself and which is never imported.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CHASSIS_RADIUS = 0.17  # diffbot.urdf: the chassis cylinder encloses every other link seen from above
SHELF_SEED = 1_000_000  # the first ClutterReach evaluation layout: its target is inside the shelf, no straight line
# reaches it


def empty_scene(start=(0.0, 0.0, 0.0), goal=(2.5, 2.5), obstacles=()) -> dict:
    """A ClutterNav scene in the reset-options format: no obstacles unless given."""
    return {"obstacles": list(obstacles), "start": list(start), "goal": list(goal)}


def ring_pixels(frame: np.ndarray, colour: Sequence[int]) -> np.ndarray:
    """Mask (H, W) of the pixels of ``frame`` painted exactly ``colour`` (a ring's pixels: the rings of
    ``clutter_gym.util.overlay`` are drawn opaque and without anti-aliasing)."""
    return np.all(frame[:, :, :3] == np.asarray(colour, dtype=np.uint8), axis=2)


def run_benchmark(module: str, *args: str, timeout: float = 300.0) -> subprocess.CompletedProcess:
    """``python -m module args`` from the repository root, as a user runs a benchmark: tests run benchmarks in a
    process of their own rather than import them. Its exit code, stdout and stderr (text)."""
    return subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True, timeout=timeout,
                          cwd=ROOT)


def run_capped(code: str, *args: str, memory: int = 3 << 30, timeout: float = 300.0,
               env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """``python -c code args`` in a process of its own: its address space capped at ``memory`` bytes, so a runaway
    allocation ends there (a MemoryError) instead of taking the machine, and killed after ``timeout`` s. On exit it
    writes its peak resident memory to stderr (read it with :func:`peak_mib`): the kernel's VmHWM of its own memory,
    as getrusage's maxrss also counts the parent's at the fork (pytest's, near 1 GB late in the suite). Its exit
    code, stdout and stderr."""
    prelude = ("import atexit, re, resource, sys\n"
               f"resource.setrlimit(resource.RLIMIT_AS, ({memory}, {memory}))\n"
               "atexit.register(lambda: sys.stderr.write('peak MiB: %.0f\\n' % (int(re.search("
               "r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read()).group(1)) / 1024)))\n")
    return subprocess.run([sys.executable, "-c", prelude + code, *args], capture_output=True, text=True,
                          timeout=timeout, env=env)


def make_refusal(robot: object, cache: Path, timeout: float = 120.0) -> subprocess.CompletedProcess:
    """``gym.make("ClutterNav-v1", robot=robot)`` in a :func:`run_capped` process caching in ``cache``; it prints the
    ValueError's message, if the make raised one, and exits 0 unless something else went wrong."""
    code = ("import gymnasium as gym, clutter_gym\n"
            "try:\n"
            f"    gym.make('ClutterNav-v1', robot={robot!r})\n"
            "except ValueError as error:\n"
            "    print(error)\n")
    return run_capped(code, timeout=timeout, env={**os.environ, "XDG_CACHE_HOME": str(cache)})


def peak_mib(result: subprocess.CompletedProcess) -> float:
    """The peak resident memory, MiB, a :func:`run_capped` process reported."""
    return float(result.stderr.rpartition("peak MiB: ")[2].split()[0])


def markdown_rows(text: str) -> list[list[str]]:
    """The cells of every markdown table row in ``text`` (header rows included, separator rows left out)."""
    return [[cell.strip() for cell in line.strip()[1:-1].split(" | ")] for line in text.splitlines()
            if line.startswith("| ")]


def report_tables(report: str) -> dict[str, list[list[str]]]:
    """Each ``## section`` of a markdown report that holds a table: its title, and the rows of its first table
    (header first)."""
    tables = {}
    for section in report.split("\n## ")[1:]:
        title, _, body = section.partition("\n")
        if "\n| " in body:
            tables[title] = markdown_rows(body[body.index("\n| ") + 1:].split("\n\n", 1)[0])
    return tables


class Touch:
    """Unpickling this creates a file: the stand-in for code a crafted pickle runs."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def copy_run(run, tmp_path):
    """A copy of the run folder of ``run`` (a ``RunDir``) in ``tmp_path / "copy"``, as a ``RunDir``, to tamper with."""
    from clutter_gym.training.run_dir import RunDir  # imported here: most tests that use helpers need no training

    shutil.copytree(run.root, tmp_path / "copy")
    return RunDir(tmp_path / "copy")
