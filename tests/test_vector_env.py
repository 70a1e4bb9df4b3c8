"""The envs' ``vector_entry_point`` (clutter_gym.vector.BlockVectorEnv): what ``gym.make_vec`` gives by default, the
same observations, rewards, ends and infos as Gymnasium's ``SyncVectorEnv`` across autoresets whatever the split
over workers, and clear errors at its boundary."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import textwrap
import threading

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
    ("ClutterNav-v1", 3, {"max_episode_steps": 12, "terminate_on_collision": True}),
    ("ClutterReach-v1", 2, {"max_episode_steps": 8}),
    ("ClutterFly-v1", 2, {"max_episode_steps": 10}),
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
    envs = gym.make_vec("ClutterNav-v1", num_envs=2, workers=1)
    try:
        assert isinstance(envs.unwrapped, BlockVectorEnv) and envs.unwrapped.processes == []
        obs, _ = envs.reset(seed=[3, 4])
        single = gym.make("ClutterNav-v1")
        np.testing.assert_array_equal(obs["lidar"][1], single.reset(seed=4)[0]["lidar"])
        single.close()
        assert envs.get_attr("spec")[0].id == "ClutterNav-v1"
        envs.set_attr("marker", [1, 2])
        assert envs.get_attr("marker") == (1, 2)
    finally:
        envs.close()


def test_close_stops_the_workers_and_errors_come_back_named():
    envs = BlockVectorEnv("ClutterNav-v1", num_envs=2, workers=2)
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
        BlockVectorEnv("ClutterNav-v1", **kwargs)


def test_a_bad_env_argument_is_named_and_leaves_no_worker():
    before = set(multiprocessing.active_children())
    with pytest.raises(ValueError, match="n_rays"):
        gym.make_vec("ClutterNav-v1", num_envs=2, workers=2, n_rays=0)
    assert set(multiprocessing.active_children()) <= before


def test_a_wrong_number_of_seeds_or_values_and_a_reset_mask_are_named():
    envs = BlockVectorEnv("ClutterNav-v1", num_envs=2, workers=1)
    try:
        with pytest.raises(ValueError, match="a list of 2 seeds"):
            envs.reset(seed=[1, 2, 3])
        with pytest.raises(ValueError, match="a list of 2, got 3"):
            envs.set_attr("marker", [1, 2, 3])
        with pytest.raises(ValueError, match="reset_mask"):
            envs.reset(options={"reset_mask": np.array([True, False])})
    finally:
        envs.close()


def run_script(body: str, timeout: float = 240.0) -> subprocess.CompletedProcess:
    """``body`` in a fresh interpreter (a case that could hang or leave processes behind stays out of the test's),
    with ``BlockVectorEnv``, ``np``, ``os``, ``signal`` and ``time`` imported."""
    script = "import os, signal, time\nimport numpy as np\nfrom clutter_gym.vector import BlockVectorEnv\n" + body
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=timeout)


def test_a_killed_worker_is_named_and_close_still_ends_everything():
    """kill -9 of a worker: step raised a bare BrokenPipeError, close raised it on every call, ``closed`` stayed
    False, the local envs stayed open and the worker a zombie."""
    done = run_script(textwrap.dedent("""
        envs = BlockVectorEnv("ClutterNav-v1", num_envs=3, workers=2)
        envs.reset(seed=0)
        process = envs.processes[0]
        os.kill(process.pid, signal.SIGKILL)
        process.join(5)
        for _ in range(2):  # the step that meets the dead worker, and a later call
            try:
                envs.step(np.zeros((3, 2)))
            except RuntimeError as error:
                print("step:", type(error).__name__, error)
        envs.close()
        envs.close()
        print("closed:", envs.closed, envs.local.closed)
        try:
            os.kill(process.pid, 0)
            print("process: still there")
        except ProcessLookupError:
            print("process: reaped")
        """))
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    assert lines[0].startswith("step: WorkerLostError env worker 1 (envs 2-2, process ")
    assert "died (exit code -9, killed by SIGKILL)" in lines[0] and "close it and make a new one" in lines[0]
    assert lines[1] == lines[0]  # every later call says the same
    assert lines[2:] == ["closed: True True", "process: reaped"]


def test_a_stopped_worker_times_out_with_a_named_error_and_close_ends_it():
    """A worker stopped with SIGSTOP blocked step for ever; now the answer is awaited ``worker_timeout`` seconds."""
    done = run_script(textwrap.dedent("""
        envs = BlockVectorEnv("ClutterNav-v1", num_envs=2, workers=2, worker_timeout=3)
        envs.reset(seed=0)
        process = envs.processes[0]
        os.kill(process.pid, signal.SIGSTOP)
        began = time.monotonic()
        try:
            envs.step(np.zeros((2, 2)))
        except RuntimeError as error:
            print("waited:", time.monotonic() - began)
            print("step:", error)
        began = time.monotonic()
        envs.close()
        print("close:", time.monotonic() - began < 3, process.exitcode)
        """), timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    waited, step, close = done.stdout.splitlines()
    assert 3.0 <= float(waited.split()[1]) < 10.0
    assert step.startswith("step: env worker 1 (envs 1-1, process ")
    assert "gave no answer to 'step' within 3 s (worker_timeout): it is stopped or stuck" in step
    assert close == "close: True -9"  # killed at once, not after the grace a running worker gets


def test_a_worker_that_takes_its_time_is_awaited():
    envs = BlockVectorEnv("ClutterNav-v1", num_envs=2, workers=2, worker_timeout=60)
    try:
        envs.reset(seed=0)
        os.kill(envs.processes[0].pid, signal.SIGSTOP)
        threading.Timer(1.5, os.kill, (envs.processes[0].pid, signal.SIGCONT)).start()
        obs, rewards, *_ = envs.step(np.zeros((2, 2)))
        assert rewards.shape == (2,)
    finally:
        envs.close()


@pytest.mark.parametrize("timeout", [0, -1, float("inf"), float("nan"), "10", True])
def test_a_bad_worker_timeout_is_named(timeout):
    with pytest.raises(ValueError, match="worker_timeout must be a positive number of seconds or None"):
        BlockVectorEnv("ClutterNav-v1", num_envs=2, workers=2, worker_timeout=timeout)


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.parametrize("actions, got", [
    (np.zeros((2, 2)), r"shape \(2, 2\)"), (np.zeros((4, 2)), r"shape \(4, 2\)"), (np.zeros(2), r"shape \(2,\)"),
    (np.zeros((3, 3)), r"shape \(3, 3\)"), ([[0, 0], [0], [0, 0]], "a ragged sequence"),
], ids=["too few rows", "too many rows", "one env's action", "wrong row length", "ragged"])
def test_actions_of_the_wrong_shape_are_named_before_any_env_steps(workers, actions, got):
    """Too few rows gave "zip() argument 2 is longer than argument 1"; too many were cut short without a word."""
    envs = BlockVectorEnv("ClutterNav-v1", num_envs=3, workers=workers)
    try:
        envs.reset(seed=0)
        with pytest.raises(ValueError, match=r"actions must have shape \(3, 2\) \(one row per env\), got " + got):
            envs.step(actions)
        envs.step(np.zeros((3, 2)))  # nothing was sent: the workers still answer in turn
    finally:
        envs.close()


def test_workers_start_in_the_workers_context_not_a_fork():
    """The block env forked its workers while clutter_gym.util.workers.context() says a fork of a process holding
    pybullet clients is unsafe; the kwargs still reach them."""
    envs = BlockVectorEnv("ClutterNav-v1", num_envs=2, workers=2, max_episode_steps=5)
    try:
        assert type(envs.processes[0]).__name__ == "ForkServerProcess"
        assert envs.get_attr("spec")[1].max_episode_steps == 5
    finally:
        envs.close()
