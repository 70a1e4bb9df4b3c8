"""Long end-to-end runs (pytest -m slow): the collision cross-check and the scripted baseline over many steps."""

from __future__ import annotations

import re

import gymnasium as gym
import pytest
from helpers import run_benchmark

from clutter_gym.training.baselines import PotentialFieldNavigator

pytestmark = pytest.mark.slow


def test_fcl_and_pybullet_agree_on_contact_in_more_than_99_percent_of_steps():
    """``python -m benchmarks.fidelity.contact_agreement``, run as a user runs it."""
    run = run_benchmark("benchmarks.fidelity.contact_agreement", "--steps", "10000", "--seed", "3", timeout=1800)
    assert run.returncode == 0, run.stderr[-3000:]
    fcl = int(re.search(r"contact in (\d+) \(FCL\)", run.stdout).group(1))
    fcl_only, pybullet_only, clearance_mm = re.search(
        r"FCL only (\d+), pybullet only (\d+); FCL clearance at a disagreement <= ([\d.]+) mm", run.stdout).groups()
    assert fcl > 1000, "the rollout should be contact-heavy"
    assert (int(fcl_only) + int(pybullet_only)) / 10000 < 0.01
    assert float(clearance_mm) < 3.0  # disagreements only at grazing contact


def test_scripted_navigator_reaches_some_goals_without_touching_anything():
    env = gym.make("ClutterNav-v1")
    successes = contacts = 0
    for episode in range(20):
        obs, _ = env.reset(seed=1000 + episode)
        policy = PotentialFieldNavigator.for_env(env)
        while True:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            contacts += info["n_contacts"] > 0
            if terminated or truncated:
                break
        successes += info["is_success"]
    env.close()
    assert successes >= 5 and contacts == 0
