"""Evaluate a trained run under a chosen noise profile: rates and means with 95% intervals, and a video."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm import tqdm

from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.training.agent import load
from clutter_gym.training.episode_stats import EpisodeStats
from clutter_gym.training.stats import mean_interval, wilson_interval
from clutter_gym.util.video import write_video

#: Metric names of an evaluation summary, each {"value", "ci95": [low, high]}; also sweep.csv's column order.
METRICS = ("success_rate", "collision_rate", "mean_cost", "mean_return", "mean_length", "mean_min_clearance")


def evaluate(
    run_dir: str | Path,
    noise: str,
    episodes: int,
    seed: int,
    video: str | Path | None = None,
    env_overrides: dict[str, Any] | None = None,
    trust_pickle: bool = False,
    progress: bool = False,
) -> dict[str, Any]:
    """Roll out ``episodes`` episodes of the run's policy; episode ``i`` is reset with seed ``seed + i``.

    Seeds fix the layouts independently of the noise profile, so evaluations of one run under two profiles see
    the same scenes (a paired comparison). The env takes the run's ``env_kwargs`` (and its noise-section
    overrides, on top of ``noise``), updated by ``env_overrides``. ``trust_pickle`` reads the normalisation
    statistics of a run written by clutter-gym 0.1, which are a pickle (see :func:`~clutter_gym.training.load`).
    ``progress`` shows a bar of the episodes on stderr.

    Returns:
        JSON-ready summary: run, env, noise profiles, env overrides, seed, the model's training step, ``metrics``
        (see ``METRICS``; rates with Wilson intervals, means with Student t intervals) and ``per_episode`` rows.
    """
    if noise not in PROFILE_NAMES:
        raise ValueError(f"noise must be one of {PROFILE_NAMES}, got {noise!r}")
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be an integer >= 1, got {episodes!r}")
    agent = load(run_dir, trust_pickle=trust_pickle)
    overrides = dict(env_overrides or {})
    noise_spec = {"profile": noise, **overrides.pop("noise", {})}
    env = agent.make_env(noise=noise_spec, render_mode="rgb_array" if video else None, **overrides)
    try:
        rows = rollouts(env, agent.predict, episodes, seed, video, progress=progress)
    finally:
        env.close()
    return {
        "run": str(agent.run.root),
        "env_id": agent.config.env_id,
        "train_noise": agent.config.noise,
        "eval_noise": noise,
        "env_overrides": dict(env_overrides or {}),
        "seed": seed,
        "episodes": episodes,
        "model": str(agent.folder.relative_to(agent.run.root)),
        "model_step": agent.step,
        "metrics": summarize(rows),
        "video": None if video is None else str(video),
        "per_episode": rows,
    }


def rollouts(env: gym.Env, policy: Callable[[Any, Any], tuple[np.ndarray, Any]], episodes: int, seed: int,
             video: str | Path | None = None, progress: bool = False) -> list[dict[str, float]]:
    """``info["episode_stats"]`` of ``episodes`` episodes of ``policy`` in ``env`` (episode ``i`` reset with seed
    ``seed + i``); the first one is written to ``video`` if given (the env must render ``rgb_array``).

    ``policy(obs, state) -> (action, state)`` as :meth:`Agent.predict`; ``state`` is None at each episode start.
    """
    env = EpisodeStats(env)
    rows, frames = [], []
    for i in tqdm(range(episodes), desc="evaluation", unit="episode", disable=not progress, dynamic_ncols=True):
        obs, _ = env.reset(seed=seed + i)
        state, record = None, video is not None and i == 0
        if record:
            frames.append(env.render())
        while True:
            action, state = policy(obs, state)
            obs, _, terminated, truncated, info = env.step(action)
            if record:
                frames.append(env.render())
            if terminated or truncated:
                rows.append(info["episode_stats"])
                break
    if video is not None:
        write_video(video, frames, fps=env.metadata["render_fps"])
    return rows


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
