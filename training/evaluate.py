"""Evaluate a trained run under a chosen noise profile: rates and means with 95% intervals, and a video."""

from __future__ import annotations

import math
import pickle
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3 import PPO

from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.training.run_dir import MODEL_FILE, NORMALIZER_FILE, RunDir
from clutter_gym.training.stats import mean_interval, wilson_interval
from clutter_gym.training.vec_env import make_env
from clutter_gym.video import write_video

#: Metric names of an evaluation summary, each {"value", "ci95": [low, high]}.
METRICS = ("success_rate", "collision_rate", "mean_cost", "mean_return", "mean_length", "mean_min_clearance")


class TrainedPolicy:
    """A run's PPO policy with the observation normalisation it was trained with; deterministic actions."""

    def __init__(self, folder: Path) -> None:
        self.model = PPO.load(folder / MODEL_FILE, device="cpu")
        self.normalizer = None
        if (folder / NORMALIZER_FILE).is_file():
            with (folder / NORMALIZER_FILE).open("rb") as f:
                self.normalizer = pickle.load(f)  # VecNormalize without its env: normalize_obs needs only stats

    def __call__(self, obs: dict[str, np.ndarray] | np.ndarray) -> np.ndarray:
        batch = {k: v[None] for k, v in obs.items()} if isinstance(obs, dict) else obs[None]
        if self.normalizer is not None and self.normalizer.norm_obs:
            batch = self.normalizer.normalize_obs(batch)
        action, _ = self.model.predict(batch, deterministic=True)
        return action[0]


def evaluate(
    run_dir: str | Path,
    noise: str,
    episodes: int,
    seed: int,
    video: str | Path | None = None,
) -> dict[str, Any]:
    """Roll out ``episodes`` episodes of the run's policy; episode ``i`` is reset with seed ``seed + i``.

    Seeds fix the layouts independently of the noise profile, so evaluations of one run under two profiles see
    the same scenes (a paired comparison). The env takes the run's ``env_kwargs``; only the noise changes.

    Returns:
        JSON-ready summary: run, env, noise profiles, seed, the model's training step, ``metrics`` (see
        ``METRICS``; rates with Wilson intervals, means with Student t intervals) and ``per_episode`` rows.
    """
    if noise not in PROFILE_NAMES:
        raise ValueError(f"noise must be one of {PROFILE_NAMES}, got {noise!r}")
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be an integer >= 1, got {episodes!r}")
    run = RunDir(run_dir)
    config = run.read_config()
    folder = run.policy_folder()
    policy = TrainedPolicy(folder)
    env = make_env(config.env_id, noise, config.env_kwargs, render_mode="rgb_array" if video else None)
    rows, frames = [], []
    try:
        for i in range(episodes):
            obs, _ = env.reset(seed=seed + i)
            record = video is not None and i == 0
            if record:
                frames.append(env.render())
            while True:
                obs, _, terminated, truncated, info = env.step(policy(obs))
                if record:
                    frames.append(env.render())
                if terminated or truncated:
                    rows.append(info["episode_stats"])
                    break
        if video is not None:
            write_video(video, frames, fps=env.metadata["render_fps"])
    finally:
        env.close()
    return {
        "run": str(run.root),
        "env_id": config.env_id,
        "train_noise": config.noise,
        "eval_noise": noise,
        "seed": seed,
        "episodes": episodes,
        "model": str(folder.relative_to(run.root)),
        "model_step": int(policy.model.num_timesteps),
        "metrics": summarize(rows),
        "video": None if video is None else str(video),
        "per_episode": rows,
    }


def summarize(rows: list[dict[str, float]]) -> dict[str, dict[str, Any]]:
    """Rates and means over episode rows (``EpisodeStats`` entries), each with its 95% interval."""
    n = len(rows)
    metrics: dict[str, dict[str, Any]] = {}
    for name, key in (("success_rate", "success"), ("collision_rate", "collision")):
        k = int(sum(r[key] for r in rows))
        metrics[name] = {"value": k / n, "ci95": list(wilson_interval(k, n))}
    for name, key in (("mean_cost", "cost"), ("mean_return", "return"), ("mean_length", "length"),
                      ("mean_min_clearance", "min_clearance")):
        values = np.array([r[key] for r in rows], dtype=float)
        values = values[np.isfinite(values)]
        if values.size == 0:
            metrics[name] = {"value": math.nan, "ci95": [math.nan, math.nan]}
            continue
        metrics[name] = {"value": float(values.mean()), "ci95": list(mean_interval(values))}
    return metrics
