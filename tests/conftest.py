"""Shared fixtures (plain helpers are in helpers.py): envs that are always closed, and one run of the
speed-against-error report, which two test files read."""

from __future__ import annotations

import gymnasium as gym
import pytest
from helpers import run_benchmark

import clutter_gym  # noqa: F401  (registers the envs)


@pytest.fixture
def make_env():
    """Factory for gym.make(...) envs that closes every env it made."""
    made = []

    def factory(env_id: str = "ClutterNav-v1", **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield factory
    for env in made:
        env.close()


@pytest.fixture(scope="session")
def speed_vs_error_report(tmp_path_factory):
    """The folder of ``python -m benchmarks.speed_vs_error --quick`` for two sections, run as a user runs it: the
    LIDAR ray count (its speed a time per scan) and ClutterFly-v1's aerodynamics (its speed a rate)."""
    out = tmp_path_factory.mktemp("speed-vs-error")
    run = run_benchmark("benchmarks.speed_vs_error", "--quick", "--sections", "lidar-rays", "aero", "--out", str(out))
    assert run.returncode == 0, run.stderr[-3000:]
    return out
