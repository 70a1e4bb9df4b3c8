"""The envs' ``vector_entry_point`` (clutter_gym.vector.BlockVectorEnv): what ``gym.make_vec`` gives by default, the
same observations, rewards, ends and infos as Gymnasium's ``SyncVectorEnv`` across autoresets whatever the split
over workers, and clear errors at its boundary."""

from __future__ import annotations

import multiprocessing

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym.vector import BlockVectorEnv


def assert_same(a, b, where: str) -> None:
    """Equal values and dtypes, dicts key by key (Gymnasium's info layout)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), f"{where}: keys differ by {a.keys() ^ b.keys()}"
        for key in a:
            assert_same(a[key], b[key], f"{where}[{key!r}]")
        return
    assert a.dtype == b.dtype and a.shape == b.shape, f"{where}: {a.dtype} {a.shape} vs {b.dtype} {b.shape}"
    if a.dtype == object:  # None, tuples or arrays, env by env
        for x, y in zip(a, b):
            assert type(x) is type(y) and (x is None or np.array_equal(np.asarray(x), np.asarray(y))), where
    else:
        np.testing.assert_array_equal(a, b, err_msg=where)


@pytest.mark.parametrize(("env_id", "num_envs", "kwargs"), [
    ("ClutterNav-v0", 3, {"max_episode_steps": 12, "terminate_on_collision": True}),
    ("ClutterReach-v0", 2, {"max_episode_steps": 8}),
    ("ClutterFly-v0", 2, {"max_episode_steps": 10}),
])
def test_blocks_over_two_workers_step_as_one_sync_vector_env(env_id, num_envs, kwargs):
    """Seeded alike and given the same actions, the block vector env over two workers (uneven blocks for
    ClutterNav) and Gymnasium's SyncVectorEnv agree bit for bit over 25 steps, two or more autoresets included."""
    sync = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="sync", **kwargs)
    blocks = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", workers=2, **kwargs)
    try:
        assert isinstance(blocks.unwrapped, BlockVectorEnv) and len(blocks.unwrapped.processes) == 1
        assert blocks.single_observation_space == sync.single_observation_space
        assert blocks.observation_space == sync.observation_space and blocks.action_space == sync.action_space
        assert blocks.metadata["autoreset_mode"] == sync.metadata["autoreset_mode"]
        for name, a, b in zip(("obs", "info"), sync.reset(seed=7), blocks.reset(seed=7)):
            assert_same(a, b, f"reset {name}")
        rng = np.random.default_rng(0)
        ends = 0
        for t in range(25):
            actions = rng.uniform(-1, 1, sync.action_space.shape).astype(np.float32)
            a, b = sync.step(actions), blocks.step(actions)
            for name, x, y in zip(("obs", "reward", "terminated", "truncated", "info"), a, b):
                assert_same(x, y, f"step {t} {name}")
            ends += int(np.sum(a[2] | a[3]))
        assert ends >= 2
    finally:
        sync.close()
        blocks.close()


def test_it_is_make_vecs_default_and_one_worker_stays_in_process():
    envs = gym.make_vec("ClutterNav-v0", num_envs=2, workers=1)
    try:
        assert isinstance(envs.unwrapped, BlockVectorEnv) and envs.unwrapped.processes == []
        obs, _ = envs.reset(seed=[3, 4])
        single = gym.make("ClutterNav-v0")
        np.testing.assert_array_equal(obs["lidar"][1], single.reset(seed=4)[0]["lidar"])
        single.close()
        assert envs.get_attr("spec")[0].id == "ClutterNav-v0"
        envs.set_attr("marker", [1, 2])
        assert envs.get_attr("marker") == (1, 2)
    finally:
        envs.close()


def test_close_stops_the_workers_and_errors_come_back_named():
    envs = BlockVectorEnv("ClutterNav-v0", num_envs=2, workers=2)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="action must be finite"):
        envs.step(np.full((2, 2), np.nan))
    envs.step(np.zeros((2, 2)))  # the worker survives its env's error
    process = envs.processes[0]
    envs.close()
    assert not process.is_alive()
    with pytest.raises(RuntimeError, match="closed"):
        envs.step(np.zeros((2, 2)))


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"num_envs": 0}, "num_envs must be an integer of at least 1"),
    ({"num_envs": 2, "workers": 3}, r"workers must be an integer in \[1, 2\]"),
])
def test_bad_counts_name_the_field(kwargs, match):
    with pytest.raises(ValueError, match=match):
        BlockVectorEnv("ClutterNav-v0", **kwargs)


def test_a_bad_env_argument_is_named_and_leaves_no_worker():
    before = set(multiprocessing.active_children())
    with pytest.raises(ValueError, match="n_rays"):
        gym.make_vec("ClutterNav-v0", num_envs=2, workers=2, n_rays=0)
    assert set(multiprocessing.active_children()) <= before


def test_a_wrong_number_of_seeds_or_values_and_a_reset_mask_are_named():
    envs = BlockVectorEnv("ClutterNav-v0", num_envs=2, workers=1)
    try:
        with pytest.raises(ValueError, match="a list of 2 seeds"):
            envs.reset(seed=[1, 2, 3])
        with pytest.raises(ValueError, match="a list of 2, got 3"):
            envs.set_attr("marker", [1, 2, 3])
        with pytest.raises(ValueError, match="reset_mask"):
            envs.reset(options={"reset_mask": np.array([True, False])})
    finally:
        envs.close()
