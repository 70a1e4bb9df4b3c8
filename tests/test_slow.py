"""Long end-to-end runs (pytest -m slow): the collision cross-check and the scripted baseline over many steps."""

from __future__ import annotations

import gymnasium as gym
import pytest

from benchmarks.fidelity.contact_agreement import measure
from clutter_gym.training.baselines import PotentialFieldNavigator

pytestmark = pytest.mark.slow


def test_fcl_and_pybullet_agree_on_contact_in_more_than_99_percent_of_steps():
    result = measure(steps=10000, seed=3)
    assert result["fcl"] > 1000, "the rollout should be contact-heavy"
    assert result["disagreement_rate"] < 0.01
    assert result["max_clearance_at_disagreement_mm"] < 3.0  # disagreements only at grazing contact


def test_scripted_navigator_reaches_some_goals_without_touching_anything():
    env = gym.make("ClutterNav-v0")
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
