"""Frame stacking: the agent's stack of recent observations matches what SB3's VecFrameStack trained the policy on."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from gymnasium import spaces
from stable_baselines3.common.vec_env import DummyVecEnv, VecFrameStack
from stable_baselines3.common.vec_env.stacked_observations import StackedObservations

from clutter_gym.training import load, normalizer
from clutter_gym.training.config import config_for
from clutter_gym.training.memory import frame_space, push_frame
from clutter_gym.training.normalizer import NORMALIZER_FILE
from clutter_gym.training.train import start, train
from clutter_gym.training.vec_env import make_env

TINY = {"timesteps": 128, "n_envs": 1, "checkpoint_every": 128, "final_eval_episodes": 0, "frame_stack": 3,
        "env_kwargs": {"obstacle_density": 0.05}, "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1}}


def test_frame_space_undoes_the_stacked_space():
    space = spaces.Dict({"a": spaces.Box(-1.0, 2.0, shape=(4,)), "b": spaces.Box(0.0, 1.0, shape=(2, 3))})
    stacked = StackedObservations(1, 5, space).stacked_observation_space  # what VecFrameStack exposes
    assert stacked["a"].shape == (20,) and stacked["b"].shape == (2, 15)
    assert frame_space(stacked, 5) == space


def test_push_frame_keeps_the_newest_frames_last_and_zeros_before_the_episode():
    space = spaces.Box(-10.0, 10.0, shape=(2,))
    stacked, state = push_frame(np.array([[1.0, 2.0]]), None, 3, space)
    np.testing.assert_array_equal(stacked, [[0, 0, 0, 0, 1, 2]])
    for frame in ([3.0, 4.0], [5.0, 6.0], [7.0, 8.0]):
        stacked, state = push_frame(np.array([frame]), state, 3, space)
    np.testing.assert_array_equal(stacked, [[3, 4, 5, 6, 7, 8]])


@pytest.fixture(scope="module")
def stacked_run(tmp_path_factory):
    run = start(config_for("ClutterNav-v1", TINY), tmp_path_factory.mktemp("stack") / "run")
    train(run, progress=False)
    return run


def test_a_loaded_stacking_agent_acts_as_the_training_pipeline(stacked_run):
    """Agent.predict on plain env observations gives the actions the model gives behind the training wrappers."""
    agent = load(stacked_run.root)
    config = agent.config
    reference = normalizer.wrap(DummyVecEnv([functools.partial(make_env, config.env_id, config.make_kwargs())]),
                                agent.folder / NORMALIZER_FILE, config)
    reference.training, reference.norm_reward = False, False
    reference = VecFrameStack(reference, config.frame_stack)
    env = agent.make_env()
    reference.seed(5)
    stacked_obs = reference.reset()
    obs, _ = env.reset(seed=5)
    state = None
    for _ in range(25):
        action, state = agent.predict(obs, state)
        expected, _ = agent.model.predict(stacked_obs, deterministic=True)
        np.testing.assert_allclose(action, expected[0], rtol=1e-6, atol=1e-6)
        obs, _, terminated, truncated, _ = env.step(action)
        stacked_obs, _, dones, _ = reference.step(expected)
        assert not (terminated or truncated or dones[0])
    assert state is not None
    env.close()
    reference.close()


def test_a_stacking_agent_takes_batches_and_names_bad_shapes(stacked_run):
    agent = load(stacked_run.root)
    env = agent.make_env()
    obs, _ = env.reset(seed=0)
    batch = {key: np.stack([value, value]) for key, value in obs.items()}
    actions, state = agent.predict(batch)
    single, _ = agent.predict(obs)
    np.testing.assert_allclose(actions[0], single, atol=1e-6)
    assert actions.shape == (2, 2)
    with pytest.raises(ValueError, match=r"obs\['lidar'\] must have shape"):
        agent.predict({**obs, "lidar": obs["lidar"][:5]})
    env.close()

