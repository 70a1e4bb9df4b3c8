"""Safety-Gymnasium style per-cause costs: ``info["cost_<cause>"]`` beside ``info["cost"]``, summing to it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym.tasks.terms import cost_by_cause

CAUSES = {"ClutterNav-v1": ("contact",), "ClutterReach-v1": ("contact", "self_contact", "tunneling"),
          "ClutterFly-v1": ("contact", "tunneling")}
# Settings under which random actions touch things often within a few hundred steps.
KWARGS = {"ClutterNav-v1": {"obstacle_density": 0.3}, "ClutterReach-v1": {"collision_fidelity": "primitive"},
          "ClutterFly-v1": {"obstacle_density": 0.25}}


def test_the_first_cause_that_holds_takes_the_step_cost():
    assert cost_by_cause(contact=False, self_contact=True, tunneling=True) == {
        "contact": 0.0, "self_contact": 1.0, "tunneling": 0.0}
    assert cost_by_cause(contact=False, tunneling=False) == {"contact": 0.0, "tunneling": 0.0}


@pytest.mark.parametrize("env_id", list(CAUSES))
def test_per_cause_costs_sum_to_cost_on_seeded_rollouts(env_id):
    env = gym.make(env_id, **KWARGS[env_id])
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    costly = 0
    for _ in range(400):
        _, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
        costs = {cause: info[f"cost_{cause}"] for cause in CAUSES[env_id]}
        assert {key for key in info if key.startswith("cost_")} == {f"cost_{c}" for c in CAUSES[env_id]}
        assert sum(costs.values()) == info["cost"] and set(costs.values()) <= {0.0, 1.0}
        assert costs["contact"] == float(info["n_contacts"] > 0)  # the first cause is never shadowed
        if "self_contact" in costs:
            assert costs["self_contact"] == float(info["self_collision"] is not None and not info["n_contacts"])
        costly += info["cost"] > 0
        if terminated or truncated:
            env.reset()
    env.close()
    assert costly > 0, "the rollout must meet at least one costly step"
