"""WorkerVecEnv: several envs per worker process must behave exactly like the same envs stepped in one process."""

from __future__ import annotations

import functools

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv

from clutter_gym.training.config import config_for
from clutter_gym.training.vec_env import build_vec_env, make_env
from clutter_gym.training.worker_vec_env import WorkerVecEnv


def cartpole() -> gym.Env:
    return Monitor(gym.make("CartPole-v1"))


def rollout(venv, steps: int, seed: int) -> list:
    """Observations, rewards, dones and terminal observations of ``steps`` fixed-pattern vector steps."""
    venv.seed(seed)
    out = [venv.reset()]
    for t in range(steps):
        actions = np.array([(t // 3 + i) % 2 for i in range(venv.num_envs)])
        obs, rewards, dones, infos = venv.step(actions)
        out += [obs, rewards, dones, [info.get("terminal_observation") for info in infos]]
    return out


def assert_same(a, b) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if isinstance(x, dict):
            assert x.keys() == y.keys()
            for key in x:
                np.testing.assert_array_equal(x[key], y[key])
        elif isinstance(x, list):
            for u, v in zip(x, y, strict=True):
                assert (u is None) == (v is None)
                if u is not None:
                    np.testing.assert_array_equal(u, v)
        else:
            np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_any_split_retraces_the_single_process_vector_exactly(workers):
    reference = DummyVecEnv([cartpole] * 5)
    venv = WorkerVecEnv([cartpole] * 5, workers=workers)
    try:
        expected, got = rollout(reference, 60, seed=7), rollout(venv, 60, seed=7)
        assert any(d.any() for d in expected[3::4]), "no episode ended: auto-reset untested"
        assert_same(expected, got)
    finally:
        venv.close()


def test_attributes_and_methods_reach_the_right_env():
    venv = WorkerVecEnv([cartpole] * 5, workers=2)
    try:
        assert [b for b in venv.blocks] == [(0, 2), (2, 5)]
        venv.set_attr("tag", "odd", indices=[1, 3])
        assert venv.get_attr("tag", indices=[3, 1]) == ["odd", "odd"]
        assert venv.env_method("get_wrapper_attr", "tag", indices=[1]) == ["odd"]
        with pytest.raises(AttributeError):
            venv.get_attr("tag", indices=[0])
        assert venv.env_is_wrapped(Monitor) == [True] * 5
        assert len(venv.get_attr("spec")) == 5
    finally:
        venv.close()


def test_bad_worker_counts_name_the_field():
    with pytest.raises(ValueError, match=r"workers must be an integer in \[1, 2\]"):
        WorkerVecEnv([cartpole] * 2, workers=3)


def test_training_envs_split_over_workers_step_like_one_process():
    config = config_for("ClutterNav-v1", {"n_envs": 3, "env_workers": 2, "env_kwargs": {"obstacle_density": 0.05}})
    venv = build_vec_env(config, seed=11)
    reference = DummyVecEnv([functools.partial(make_env, config.env_id, config.make_kwargs())] * 3)
    try:
        assert isinstance(venv, WorkerVecEnv)
        reference.seed(11)
        expected_first, got_first = reference.reset(), venv.reset()
        assert_same([expected_first], [got_first])
        actions = np.random.default_rng(0).uniform(-1, 1, size=(20, 3, 2)).astype(np.float32)
        for a in actions:
            assert_same(list(reference.step(a)[:3]), list(venv.step(a)[:3]))
    finally:
        venv.close()
        reference.close()


@pytest.mark.parametrize("bad", [0, 2], ids=["in this process", "in a worker process"])
def test_an_env_error_reaches_the_caller_and_leaves_the_vector_usable(bad):
    venv = WorkerVecEnv([cartpole] * 4, workers=2)
    try:
        venv.reset()
        actions = np.array([0, 1, 1, 0])
        actions[bad] = 7
        with pytest.raises(AssertionError):  # CartPole asserts its action space
            venv.step(actions)
        obs, rewards, _, _ = venv.step(np.array([0, 1, 1, 0]))  # the other block's reply did not stay in its pipe
        assert rewards.shape == (4,) and obs.shape == (4, 4)
        assert len(venv.processes) == 1  # the first block steps in this process
    finally:
        venv.close()
