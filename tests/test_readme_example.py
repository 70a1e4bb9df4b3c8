"""The README's first code example runs as a user would run it: a fresh interpreter, the installed package."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_first_example_runs():
    block = re.search(r"```python\n(.*?)```", README.read_text(), re.S).group(1)
    assert "gym.make_vec" in block  # the vector route is part of it
    done = subprocess.run([sys.executable, "-c", block + "\nvec.step(vec.action_space.sample())\nvec.close()\n"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]


def test_the_agent_example_runs_on_a_shipped_agent():
    block = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)[1]
    assert 'load("pretrained/' in block  # runs without training first
    done = subprocess.run([sys.executable, "-c", block], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split()[0] in ("True", "False")
