"""What the main job shows while it runs and what it writes for a README: a training bar whose total is the step
training ends at, a bar while the episode GIF is drawn, and a GIF small enough to embed (issue 53.5)."""

from __future__ import annotations

import gymnasium as gym
import imageio.v2 as imageio

from clutter_gym.training.baselines import PotentialFieldNavigator
from clutter_gym.training.config import config_for
from clutter_gym.training.episode_view import record_episode, write_episodes_video
from clutter_gym.training.train import start, train


def test_the_training_bar_ends_at_its_total(tmp_path, capsys):
    """A budget of 100 steps in rollouts of 64 trains 128 steps: the bar's total says 128 (a bar that runs past its
    total drops it, and ended as ``128step``)."""
    config = config_for("ClutterNav-v1", {"timesteps": 100, "n_envs": 1, "checkpoint_every": 1000,
                                          "validate_every": 0, "final_eval_episodes": 0,
                                          "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1}})
    train(start(config, tmp_path / "run"), progress=True)
    bar = capsys.readouterr().err.replace("\r", "\n").strip().splitlines()[-1]
    assert "128/128" in bar, bar


def test_two_full_length_episodes_make_a_gif_a_readme_can_embed_and_a_bar_shows_the_drawing(tmp_path, capsys):
    """The longest evaluation episodes (400 steps, the time limit) side by side: under 2.5 MB (11 MB before, in
    201 frames of 1040 x 580 drawn without a word on the terminal)."""
    env = gym.make("ClutterNav-v1", subgoal_lookahead=0.5)
    navigator = PotentialFieldNavigator.for_env(env)  # goal-seeking only: it gets stuck in the clutter of these
    traces = [record_episode(env, lambda obs, state: (navigator(obs), None), seed, f"failure, seed {seed}")
              for seed in (1, 2)]
    env.close()
    assert [len(t.poses) for t in traces] == [401, 401]
    path = write_episodes_video(tmp_path / "episode.gif", traces, fps=20.0, progress=True)
    assert "drawing episode.gif" in capsys.readouterr().err
    frames = imageio.mimread(path)
    assert len(frames) == 51 and frames[0].shape[:2] == (435, 720)  # every 8th step of 400, and the last
    assert path.stat().st_size < 2.5 * 2**20, path.stat().st_size
