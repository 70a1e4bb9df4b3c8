"""Gymnasium API, determinism and lifecycle for every registered env id."""

from __future__ import annotations

import copy
import gc
import os
import pickle
from fractions import Fraction

import gymnasium as gym
import numpy as np
import psutil
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from clutter_gym import ENV_IDS
from clutter_gym.sim import pb

INFO_KEYS = {"reward_terms", "cost", "is_success", "min_clearance", "closest_pair", "witness_points", "n_contacts",
             "max_penetration", "self_collision", "tunneling", "pybullet_contacts", "contact_disagreement"}


def rollout(env, seed: int, steps: int, action_seed: int = 7):
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(action_seed)
    out = [obs]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, size=env.action_space.shape))
        out.append((obs, reward, terminated, info["min_clearance"]))
        if terminated or truncated:
            obs, _ = env.reset()
    return out


def assert_same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if isinstance(x, dict):
            x, y = (x,), (y,)
        for u, v in zip(x, y):
            if isinstance(u, dict):
                assert u.keys() == v.keys()
                for key in u:
                    np.testing.assert_array_equal(u[key], v[key])
            else:
                assert u == v


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_check_env(env_id, make_env):
    # The human render mode needs a display; it is checked under Xvfb in test_render.py.
    check_env(make_env(env_id).unwrapped, skip_render_check=not os.environ.get("DISPLAY"))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env(env_id, make_env):
    sb3_check_env(make_env(env_id), warn=True)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_lockstep_determinism(env_id, make_env):
    a, b = make_env(env_id), make_env(env_id)
    assert_same(rollout(a, seed=3, steps=120), rollout(b, seed=3, steps=120))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_after_a_different_history(env_id, make_env):
    fresh, used = make_env(env_id), make_env(env_id)
    for seed in (11, 12, 13):
        rollout(used, seed=seed, steps=40)
    assert_same(rollout(fresh, seed=5, steps=80), rollout(used, seed=5, steps=80))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_reset_to_the_same_start_right_after_a_step_repeats_the_first_step(env_id, make_env):
    """Bullet keeps contact manifolds of a body reset to where it just was; reset must drop them."""
    env, fresh = make_env(env_id), make_env(env_id)
    action = np.linspace(0.3, -0.2, env.action_space.shape[0], dtype=np.float32)
    env.reset(seed=123)
    first = env.step(action)[0]
    env.reset(seed=123)
    again = env.step(action)[0]
    fresh.reset(seed=123)
    assert_same([first, fresh.step(action)[0]], [again, again])


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_different_seeds_differ(env_id, make_env):
    env = make_env(env_id)
    first, _ = env.reset(seed=1)
    second, _ = env.reset(seed=2)
    assert any(not np.array_equal(first[key], second[key]) for key in first)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_observations_stay_in_space_and_info_is_complete(env_id, make_env):
    env = make_env(env_id)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(100):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, size=env.action_space.shape))
        assert env.observation_space.contains(obs)
        assert INFO_KEYS <= info.keys()
        assert np.isfinite(reward)
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        assert info["cost"] in (0.0, 1.0)
        if terminated or truncated:
            env.reset()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_time_limit_truncates(env_id, make_env):
    env = make_env(env_id, max_episode_steps=5)
    env.reset(seed=0)
    flags = [env.step(np.zeros(env.action_space.shape))[3] for _ in range(5)]
    assert flags == [False] * 4 + [True]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_make_vec(env_id):
    envs = gym.make_vec(env_id, num_envs=2, vectorization_mode="sync")
    try:
        obs, _ = envs.reset(seed=0)
        assert all(value.shape[0] == 2 for value in obs.values())
        obs, reward, terminated, truncated, info = envs.step(np.zeros((2, *envs.single_action_space.shape), np.float32))
        assert reward.shape == (2,)
        assert any(not np.array_equal(value[0], value[1]) for value in obs.values())  # seeds 0 and 1: two layouts
    finally:
        envs.close()


@pytest.mark.parametrize(
    "action, message",
    [([np.nan, 0.0], "finite"), ([0.0, np.inf], "finite"), ([0.0], "shape"), ([[0.0, 0.0]], "shape")],
)
def test_bad_actions_raise(action, message, make_env):
    env = make_env()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(np.array(action))


@pytest.mark.parametrize("env_id", ["ClutterNav-v1", "ClutterReach-v1"])
@pytest.mark.parametrize(
    "action", ["ab", None, {"v": 1.0}, [object(), object()], [1.0, "a"], [[0.0], [0.0, 1.0]], True, [True, False],
               [1j, 0.0], np.array([True, 0.5], dtype=object), np.array([np.bool_(False), 0.5], dtype=object),
               np.array([None, 0.5], dtype=object), np.array(["0.1", 0.5], dtype=object),
               np.array([1j, 0.5], dtype=object), np.array([np.complex64(1), 0.5], dtype=object),
               np.array([np.array([0.1]), 0.5], dtype=object)],
    ids=["str", "None", "dict", "objects", "mixed", "ragged", "bool", "bools", "complex", "object-bool",
         "object-numpy-bool", "object-None", "object-str", "object-complex", "object-numpy-complex", "object-array"],
)
def test_actions_that_are_not_real_numbers_name_the_action(env_id, action, make_env):
    env = make_env(env_id)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be .* real numbers"):
        env.step(action)


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.float64, np.int8, np.int64, np.uint8, list, tuple])
def test_every_real_dtype_and_container_steps_as_float64(dtype, make_env):
    a, b = make_env(), make_env()
    a.reset(seed=4)
    b.reset(seed=4)
    action = [1, 0]
    given = dtype(action) if dtype in (list, tuple) else np.array(action, dtype=dtype)
    np.testing.assert_array_equal(a.step(given)[0]["lidar"], b.step(np.array([1.0, 0.0]))[0]["lidar"])


@pytest.mark.parametrize("action", [
    np.array([0.1, -0.2], dtype=object),
    np.array([0.1, np.float32(-0.2)], dtype=object),
    np.array([np.float16(0.1), np.float64(-0.2)], dtype=object),
    np.array([1, np.int64(-1)], dtype=object),
    np.array([np.uint8(1), Fraction(-1, 5)], dtype=object),
], ids=["floats", "float-and-float32", "float16-and-float64", "int-and-int64", "uint8-and-fraction"])
def test_object_arrays_of_real_numbers_step_as_float64(action, make_env):
    """An object array whose every element is a real number (Python's, numpy's, a Fraction) is a real action."""
    a, b = make_env(), make_env()
    a.reset(seed=4)
    b.reset(seed=4)
    expected = np.array([float(v) for v in action])
    np.testing.assert_array_equal(a.step(action)[0]["lidar"], b.step(expected)[0]["lidar"])


def test_an_integer_too_large_for_a_float_is_not_finite(make_env):
    env = make_env()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be finite"):
        env.step(np.array([10**400, 0], dtype=object))


def test_out_of_range_actions_are_clipped(make_env):
    a, b = make_env(), make_env()
    a.reset(seed=4)
    b.reset(seed=4)
    for _ in range(10):
        obs_a, *_ = a.step(np.array([5.0, -3.0]))
        obs_b, *_ = b.step(np.array([1.0, -1.0]))
        np.testing.assert_array_equal(obs_a["lidar"], obs_b["lidar"])


def test_step_before_reset_raises(make_env):
    with pytest.raises((RuntimeError, gym.error.ResetNeeded)):
        make_env().step(np.zeros(2))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_failed_reset_refuses_steps_until_a_reset_succeeds(env_id, make_env):
    env = make_env(env_id)
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape)
    env.step(action)
    with pytest.raises(ValueError, match="unknown keys"):
        env.reset(options={"scene": {"bogus": 1}})
    with pytest.raises(RuntimeError, match=r"last reset\(\) failed \(ValueError: .*unknown keys.*call reset\(\) again"):
        env.step(action)
    env.reset(seed=0)
    env.step(action)


def test_render_rgb_array(make_env):
    env = make_env(render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (240, 320, 3) and frame.dtype == np.uint8
    assert frame.std() > 5  # a picture, not a blank buffer


@pytest.mark.parametrize(("kwargs", "draws"), [({}, False), ({"render_mode": "rgb_array"}, True),
                                              ({"sensors": ("lidar", "camera")}, True)])
def test_obstacles_have_visual_shapes_where_the_env_draws(make_env, kwargs, draws):
    """An env with neither render_mode nor camera makes its obstacles without visual shapes (pybullet stands in
    their collision shapes, white) and its Sim refuses to draw; one that draws gives them their colours."""
    env = make_env(**kwargs)
    env.reset(seed=0)
    sim = env.unwrapped.sim
    colours = {pb.getVisualShapeData(body, physicsClientId=sim.client_id)[0][7]
               for body in env.unwrapped.arena._pool.placed.values()}
    assert sim.visuals is draws
    assert (colours == {(1.0, 1.0, 1.0, 1.0)}) is not draws
    if not draws:
        with pytest.raises(RuntimeError, match="visuals=False"):
            sim.rendering.render(32, 32, (0.0, -5.0, 5.0), (0.0, 0.0, 0.0))


def test_close_frees_the_client_and_200_cycles_leak_nothing_measurable():
    process = psutil.Process()

    def cycle():
        env = gym.make("ClutterNav-v1")
        env.reset(seed=0)
        env.step(np.zeros(2))
        sim = env.unwrapped.sim
        env.close()
        assert not sim.connected

    for _ in range(20):  # warm-up: allocator pools, import caches
        cycle()
    gc.collect()
    before = process.memory_info().rss
    for _ in range(200):
        cycle()
    gc.collect()
    growth_mb = (process.memory_info().rss - before) / 2**20
    # One leaked env (pybullet world, robot, walls, FCL trees) costs several MB; 200 leaks would be >> 25 MB.
    assert growth_mb < 25, f"RSS grew {growth_mb:.1f} MB over 200 make/close cycles"


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_closed_env_says_so_instead_of_failing_inside_pybullet(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    env.close()
    env.close()  # twice is fine
    for call in (lambda: env.reset(seed=0), lambda: env.step(env.action_space.sample()), env.render):
        with pytest.raises(RuntimeError, match=f"{env_id} is closed"):
            call()


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("copier", [pickle.dumps, copy.deepcopy, copy.copy], ids=["pickle", "deepcopy", "copy"])
def test_an_env_cannot_be_pickled_or_copied_and_says_what_to_do_instead(env_id, copier, make_env):
    """An env owns a physics client and FCL objects, which cannot be serialised: the error names the env (through
    gym.make's wrappers too) and says to make a new one, not FCL's Cython that names nothing. A shallow copy would
    share the client while looking like a second env, so it is refused too (a wrapper's shallow copy is the
    wrapper's: it wraps the same env). The env still works afterwards."""
    env = make_env(env_id)
    env.reset(seed=0)
    for target in (env, env.unwrapped) if copier is not copy.copy else (env.unwrapped,):
        with pytest.raises(TypeError) as caught:
            copier(target)
        message = str(caught.value)
        assert f"{env_id} ({type(env.unwrapped).__name__})" in message and "cannot be pickled or copied" in message
        assert "physics client" in message and "gym.make" in message and "factory" in message
    env.step(env.action_space.sample())
