"""Shared fixtures (plain helpers are in helpers.py): envs that are always closed."""

from __future__ import annotations

import gymnasium as gym
import pytest

import clutter_gym  # noqa: F401  (registers the envs)


@pytest.fixture
def make_env():
    """Factory for gym.make(...) envs that closes every env it made."""
    made = []

    def factory(env_id: str = "ClutterNav-v0", **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield factory
    for env in made:
        env.close()

