"""ClutterReachGoal-v1: ClutterReach for hindsight experience replay, as panda-gym users expect it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from clutter_gym.goal_conditioned import GOAL_TERMS


@pytest.mark.parametrize("reward_type", ["sparse", "dense"])
def test_compute_reward_agrees_with_step_one_by_one_and_in_batches(reward_type):
    """Through ``env.unwrapped``, where Gymnasium-Robotics' GoalEnv and HER implementations call it."""
    env = gym.make("ClutterReachGoal-v1", reward_type=reward_type, collision_fidelity="primitive")
    compute = env.unwrapped.compute_reward
    obs, _ = env.reset(seed=2)
    assert set(obs) == {"observation", "achieved_goal", "desired_goal"} and obs in env.observation_space
    assert env.unwrapped.observation_space == env.observation_space
    rng = np.random.default_rng(0)
    achieved, desired, infos, rewards = [], [], [], []
    for _ in range(120):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 7))
        achieved.append(obs["achieved_goal"])
        desired.append(obs["desired_goal"])
        infos.append(info)
        rewards.append(reward)
        assert reward == compute(obs["achieved_goal"], obs["desired_goal"], info)
        if terminated or truncated:
            obs, _ = env.reset()
    batch = compute(np.array(achieved), np.array(desired), np.array(infos))
    np.testing.assert_array_equal(batch, np.array(rewards, dtype=np.float32))
    assert any(sum(v for k, v in i["reward_terms"].items() if k not in GOAL_TERMS) < 0 for i in infos)
    # relabelled with the goal it reached, a transition earns the goal part in full
    relabelled = compute(np.array(achieved), np.array(achieved), np.array(infos))
    assert np.all(relabelled >= batch)
    env.close()


def test_the_goal_env_passes_gymnasiums_checker_and_refuses_an_unknown_reward_type():
    env = gym.make("ClutterReachGoal-v1")
    check_env(env.unwrapped, skip_render_check=True)
    with pytest.raises(ValueError, match="copy_info_dict"):  # SB3's default stores no infos
        env.unwrapped.compute_reward(np.zeros((2, 3)), np.ones((2, 3)), np.array([{}, {}]))
    env.close()
    with pytest.raises(ValueError, match="reward_type must be one of"):
        gym.make("ClutterReachGoal-v1", reward_type="shaped")
    with pytest.raises(TypeError, match="'reward_tpye' \\(did you mean 'reward_type'\\?\\)"):
        gym.make("ClutterReachGoal-v1", reward_tpye="dense")  # named as every env names a misspelt argument


def test_her_with_sac_trains_on_it():
    from stable_baselines3 import SAC, HerReplayBuffer

    env = gym.make("ClutterReachGoal-v1")
    model = SAC("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer, learning_starts=100, batch_size=64,
                replay_buffer_kwargs={"n_sampled_goal": 4, "goal_selection_strategy": "future",
                                      "copy_info_dict": True},
                policy_kwargs={"net_arch": [64, 64]}, seed=0, device="cpu")
    model.learn(300)
    buffer = model.replay_buffer
    assert buffer.size() > 0 and model.num_timesteps == 300
    # HER's relabelled rewards come from the env's compute_reward: sampled batches hold reached goals too
    batch = buffer.sample(256)
    assert batch.rewards.shape == (256, 1) and np.isfinite(batch.rewards.cpu().numpy()).all()
    env.close()
