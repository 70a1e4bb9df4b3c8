"""Binned actions: the bins' values, the soft targets a label between two bins is learnt as, and a policy over bins
that keeps one of two modes where regression averages them."""

from __future__ import annotations

import numpy as np
import pytest
import torch as th
from gymnasium import spaces

from clutter_gym.training.binned_actions import BinnedActions, bin_values, binned_space, decode, soft_targets
from clutter_gym.training.privileged import imitation_loss


def test_bins_span_the_action_range_evenly_and_decode_to_their_values():
    np.testing.assert_allclose(bin_values(5), [-1.0, -0.5, 0.0, 0.5, 1.0])
    np.testing.assert_array_equal(decode([[0, 4], [2, 3]], 5), np.array([[-1, 1], [0, 0.5]], dtype=np.float32))
    assert binned_space(spaces.Box(-1, 1, (2,)), 9) == spaces.MultiDiscrete([9, 9])
    with pytest.raises(ValueError, match=r"needs a Box\(-1, 1, \(n,\)\) action space"):
        binned_space(spaces.Box(-2, 2, (2,)), 9)


def test_a_label_between_two_bins_is_split_between_them_by_nearness():
    target = soft_targets(th.tensor([[0.25, -1.0, 1.0, 0.1]]), 5)[0]  # bins -1, -0.5, 0, 0.5, 1
    np.testing.assert_allclose(target[0], [0, 0, 0.5, 0.5, 0])
    np.testing.assert_allclose(target[1], [1, 0, 0, 0, 0])
    np.testing.assert_allclose(target[2], [0, 0, 0, 0, 1])
    np.testing.assert_allclose(target[3], [0, 0, 0.8, 0.2, 0], atol=1e-6)
    # the expected value of the soft target is the label itself: nothing is rounded away
    np.testing.assert_allclose(target @ th.as_tensor(bin_values(5), dtype=th.float32), [0.25, -1.0, 1.0, 0.1],
                               atol=1e-6)


def test_the_wrapper_hands_the_env_the_bins_values(make_env):
    env = BinnedActions(make_env("ClutterNav-v1", sensors=["lidar"]), 9)
    assert env.action_space == spaces.MultiDiscrete([9, 9])
    np.testing.assert_array_equal(env.action(np.array([8, 0])), [1.0, -1.0])


def _fit(bins: int) -> np.ndarray:
    """A policy fitted to labels that turn hard left half the time and hard right the other half, for the same
    observation: the action it then takes."""
    from stable_baselines3.common.policies import MultiInputActorCriticPolicy

    observation_space = spaces.Dict({"x": spaces.Box(-1, 1, (3,))})
    action_space = spaces.MultiDiscrete([bins, bins]) if bins else spaces.Box(-1, 1, (2,))
    th.manual_seed(0)
    policy = MultiInputActorCriticPolicy(observation_space, action_space, lambda _: 1e-2, net_arch=[16])
    obs = {"x": th.zeros(64, 3)}
    labels = th.tensor([[-1.0, 1.0], [-1.0, -1.0]]).repeat(32, 1)
    optimizer = th.optim.Adam(policy.parameters(), lr=1e-2)
    for _ in range(300):
        loss = imitation_loss(policy, obs, labels, bins)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    action, _ = policy.predict({"x": np.zeros((1, 3), np.float32)}, deterministic=True)
    return (decode(action, bins) if bins else action)[0]


def test_regression_averages_a_left_and_right_turn_into_none_and_bins_keep_one():
    """The defect bins remove: the teacher turns hard one way or the other where the student cannot tell which;
    regression then stands still (turn 0), a categorical policy turns (docs/learning.md)."""
    assert abs(_fit(0)[1]) < 0.1
    assert abs(_fit(9)[1]) == 1.0
    assert _fit(9)[0] == -1.0
