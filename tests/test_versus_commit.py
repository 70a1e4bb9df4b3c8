"""``python -m benchmarks.speed.versus_commit``, the route for timing a change against the commit before it in one
process, run for a few blocks against HEAD: no timing is asserted, only that it builds the commit's package, makes
both envs and reports."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: The benchmark archives a commit with git: a copy of the sources without their history (a downloaded archive)
#: has none to compare with, so the test is skipped there, and only there.
IN_GIT = shutil.which("git") is not None and subprocess.run(
    ["git", "-C", str(ROOT), "rev-parse", "--verify", "HEAD"], capture_output=True).returncode == 0


@pytest.mark.skipif(not IN_GIT, reason="not a git checkout: no commit to compare with")
def test_it_builds_the_commit_and_reports_both_figures_and_the_trajectory_check():
    result = subprocess.run(
        [sys.executable, "-m", "benchmarks.speed.versus_commit", "--commit", "HEAD", "--rounds", "2", "--steps", "20",
         "--resets", "3", "--trajectory-steps", "40"],
        capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-3000:]
    # the working tree may differ from HEAD while a change is being made, so either verdict is fine
    assert re.search(r"seeded trajectories (identical \(40 steps\)|differ from step \d+)", result.stdout), result.stdout
    rows = {line.split("|")[1].strip(): line for line in result.stdout.splitlines() if line.startswith("| ")}
    for figure, unit in (("step", "µs"), ("reset", "ms")):
        assert re.fullmatch(rf"\| {figure} \| [\d.]+ {unit} \| [\d.]+ {unit} \| [\d.]+× \([\d.]+–[\d.]+\) \|",
                            rows[figure]), rows
