"""render_mode="human" opens the pybullet GUI: checked in a subprocess under a real or virtual display."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import gymnasium as gym
import pytest

HUMAN_SCRIPT = """
import gymnasium as gym, numpy as np, clutter_gym
from gymnasium.utils.env_checker import check_env
env = gym.make("ClutterNav-v1", render_mode="human")
env.reset(seed=0)
for _ in range(10):
    env.step(np.array([0.5, 0.2]))
env.close()
check_env(gym.make("ClutterNav-v1").unwrapped)  # with a display: every render mode, human included
print("human-ok")
"""


def display_command() -> list[str] | None:
    if os.environ.get("DISPLAY"):
        return []
    if shutil.which("xvfb-run"):
        return ["xvfb-run", "-a"]
    return None


@pytest.mark.skipif(display_command() is None, reason="no display and no xvfb-run (apt-get install xvfb)")
def test_human_render_mode_under_a_display():
    result = subprocess.run(
        [*display_command(), sys.executable, "-c", HUMAN_SCRIPT], capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip().endswith("human-ok")


def test_human_mode_without_a_display_fails_clearly(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    if not sys.platform.startswith("linux"):
        pytest.skip("the display check applies to Linux")
    with pytest.raises(RuntimeError, match="needs a display"):
        gym.make("ClutterNav-v1", render_mode="human")
