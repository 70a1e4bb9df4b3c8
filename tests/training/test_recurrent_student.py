"""A recurrent student (``ppo.lstm_hidden_size``): DAgger on sequences, an LSTM that remembers what a memoryless
policy cannot, and a run folder that loads, acts with its state carried, evaluates and continues as any other."""

from __future__ import annotations

import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from sb3_contrib import RecurrentPPO

from clutter_gym.training import load
from clutter_gym.training.config import config_for
from clutter_gym.training.distill_config import DistillSettings
from clutter_gym.training.evaluate import evaluate
from clutter_gym.training.policy_file import load_ppo
from clutter_gym.training.recurrent_policy import MultiInputLstmBesidePolicy
from clutter_gym.training.run_dir import MODEL_FILE
from clutter_gym.training.sequences import SequenceDataset, fit_sequences
from clutter_gym.training.train import resume_point, start, train
from clutter_gym.training.vec_env import training_env

SMALL = {"arena_size": 3.0, "obstacle_density": 0.05, "n_rays": 16, "sensors": ["lidar"], "reverse": False,
         "observe_bearing": True, "max_episode_steps": 60, "subgoal_lookahead": 0.0}


def _fill(data: SequenceDataset) -> None:
    """Seven steps of two envs whose x is the step (env 1: 10 + step); env 0's episodes start at steps 0 and 2,
    env 1's at step 0. The state before step t is (t, -t)."""
    for step in range(7):
        state = (np.full((1, 2, 2), step, np.float32), np.full((1, 2, 2), -step, np.float32))
        data.add({"x": np.array([[step], [10 + step]])}, np.array([[step], [step]]), np.ones(2),
                 np.array([step in (0, 2), step == 0]), state)


def test_the_data_set_cuts_each_envs_episodes_into_padded_sequences_with_the_state_they_start_from():
    data = SequenceDataset(max_samples=100, length=3, hidden_size=2)
    _fill(data)
    arrays = data.arrays()
    assert data.size == 11  # env 0: [0, 1] (its next episode started), [2, 3, 4]; env 1: [0, 1, 2], [3, 4, 5]
    np.testing.assert_array_equal(arrays["obs"]["x"][..., 0], [[0, 1, 0], [10, 11, 12], [2, 3, 4], [13, 14, 15]])
    np.testing.assert_array_equal(arrays["weights"], [[1, 1, 0], [1, 1, 1], [1, 1, 1], [1, 1, 1]])  # padding: 0
    np.testing.assert_array_equal(arrays["hidden"][:, 0], [0, 0, 0, 3])  # zeros where an episode starts
    np.testing.assert_array_equal(arrays["cell"][:, 0], [0, 0, 0, -3])
    trimmed = SequenceDataset(max_samples=8, length=3, hidden_size=2)
    _fill(trimmed)
    assert trimmed.size == 9 and trimmed.arrays()["obs"]["x"][0, 0, 0] == 10  # the oldest sequence dropped


def _cue_episodes(rng: np.random.Generator, envs: int, steps: int, episode: int):
    """Vector steps of ``envs`` envs whose episodes last ``episode`` steps: a cue of +-1 is seen at the episode's
    first step only (0 after), and the label at every step is the cue."""
    cues = np.zeros(envs)
    for step in range(steps):
        starts = np.full(envs, step % episode == 0)
        if starts[0]:
            cues = rng.choice([-1.0, 1.0], envs)
        yield {"x": np.where(starts, cues, 0.0)[:, None]}, cues[:, None], starts


def test_a_recurrent_fit_remembers_a_cue_that_a_memoryless_policy_cannot_see():
    """After the first step the observation is 0 whatever the cue, so a memoryless policy can only answer 0 there;
    the LSTM, fitted on sequences of two episodes each (reset at each start), must answer the cue."""
    space = spaces.Dict({"x": spaces.Box(-1, 1, (1,))})
    policy = MultiInputLstmBesidePolicy(space, spaces.Box(-1, 1, (1,)), lambda _: 1e-2, net_arch=[16],
                                                  lstm_hidden_size=16)
    th.manual_seed(0)
    data = SequenceDataset(max_samples=10_000, length=12, hidden_size=16)
    for obs, labels, starts in _cue_episodes(np.random.default_rng(0), envs=16, steps=48, episode=6):
        data.add(obs, labels, np.ones(16), starts, None)
    settings = DistillSettings(epochs=300, batch_size=768, learning_rate=1e-2, sequence_length=12)
    loss = fit_sequences(policy, data, settings, th.optim.Adam(policy.parameters(), lr=1e-2), bins=0)
    assert loss < 0.05  # a memoryless fit cannot go below the labels' variance at the blind steps, 1 x 5/6
    state, errors = None, []
    for obs, labels, starts in _cue_episodes(np.random.default_rng(1), envs=8, steps=18, episode=6):
        action, state = policy.predict(obs, state, episode_start=starts, deterministic=True)
        errors.append(np.abs(action - labels).max())
    assert max(errors) < 0.3


@pytest.mark.parametrize(("settings", "message"), [
    ({"frame_stack": 4}, "frame_stack must be 1 with ppo.lstm_hidden_size > 0"),
    ({"critic_inputs": ["subgoal"]}, "critic_inputs needs ppo.lstm_hidden_size 0"),
    ({"timesteps": 10_000}, r"timesteps must be at most the distillation's 2400 steps"),
    ({"ppo": {"lstm_hidden_size": -1}}, r"ppo.lstm_hidden_size must be a number in \[0, 4096\], got -1"),
])
def test_what_a_recurrent_student_cannot_have_is_refused_by_name(settings, message):
    base = {"teacher": {"name": "planner"}, "env_kwargs": SMALL, "timesteps": 2400,
            "distill": {"rounds": 2, "round_steps": 1000, "warmup_steps": 400}}
    with pytest.raises(ValueError, match=message):
        config_for("ClutterNav-v1", {**base, **settings, "ppo": {"lstm_hidden_size": 8, **settings.get("ppo", {})}})


def test_a_recurrent_student_is_a_run_that_loads_acts_with_its_state_evaluates_and_continues(tmp_path):
    config = config_for("ClutterNav-v1", {
        "n_envs": 2, "env_workers": 1, "timesteps": 600, "validate_episodes": 1, "final_eval_episodes": 0,
        "action_bins": 5, "residual_space": "waypoint", "teacher": {"name": "planner"}, "env_kwargs": SMALL,
        "distill": {"rounds": 2, "round_steps": 256, "warmup_steps": 88, "epochs": 2, "sequence_length": 16,
                    "batch_size": 64},
        "ppo": {"net_arch": [16], "lstm_hidden_size": 8}})
    run = start(config, tmp_path / "run")
    train(run, progress=False)
    rows = run.read_distill_rows()
    assert rows[0]["samples"] <= 256 < rows[1]["samples"] <= 512  # complete sequences only: tails wait
    assert np.isfinite(rows[1]["unseen_loss"])
    agent = load(run.root)
    assert isinstance(agent.model, RecurrentPPO) and isinstance(agent.model.policy, MultiInputLstmBesidePolicy)
    env = agent.make_env()
    obs, _ = env.reset(seed=0)
    action, state = agent.predict(obs)
    raw, expected = agent.model.predict(agent._normalizer.normalize_obs(obs), None, np.ones(1, bool),
                                        deterministic=True)
    np.testing.assert_array_equal(state[0], expected[0])  # the LSTM's state comes back to be carried
    obs, *_ = env.step(action)
    _, carried = agent.predict(obs, state)
    _, fresh = agent.predict(obs)
    assert not np.array_equal(carried[0], fresh[0])  # what it saw before changes what it holds now
    env.close()
    summary = evaluate(run.root, noise="nominal", episodes=2, seed=5)
    assert [row["length"] <= SMALL["max_episode_steps"] for row in summary["per_episode"]] == [True, True]
    step, folder, _ = resume_point(run, config)
    venv = training_env(config, seed=1)
    try:
        continued = load_ppo(folder / MODEL_FILE, config, venv.observation_space, venv.action_space, env=venv)
    finally:
        venv.close()
    assert isinstance(continued, RecurrentPPO) and continued.num_timesteps == step


def test_without_a_teacher_a_recurrent_policy_trains_with_recurrent_ppo_and_loads(tmp_path):
    config = config_for("ClutterNav-v1", {
        "n_envs": 2, "env_workers": 1, "timesteps": 64, "final_eval_episodes": 1, "env_kwargs": SMALL,
        "ppo": {"n_steps": 16, "batch_size": 16, "n_epochs": 1, "net_arch": [16], "lstm_hidden_size": 8}})
    run = start(config, tmp_path / "run")
    summary = train(run, progress=False)
    assert summary["episodes"] == 1
    agent = load(run.root)
    assert isinstance(agent.model, RecurrentPPO) and agent.step == 64
    assert agent.model.policy.lstm_actor.hidden_size == 8
