"""tasks.py, the quickstart's entry point: it makes .venv with a Python pybullet has wheels for."""

from __future__ import annotations

import tasks


def test_a_wheel_python_is_chosen_only_where_this_python_has_no_pybullet_wheel():
    on_path = {"python3.10": "/usr/bin/python3.10"}.get
    assert tasks.wheel_python((3, 11), on_path) is None
    assert tasks.wheel_python((3, 10), on_path) is None
    assert tasks.wheel_python((3, 12), on_path) == "/usr/bin/python3.10"
    both = {"python3.10": "/a/python3.10", "python3.11": "/b/python3.11"}.get
    assert tasks.wheel_python((3, 13), both) == "/b/python3.11"  # the newest with wheels
    assert tasks.wheel_python((3, 12), lambda name: None) is None  # none found: go on, compiling pybullet
