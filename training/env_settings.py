"""Checks of the ``gym.make`` arguments a training config gives its env (``env_kwargs``, ``train_env_mix``): their
names against the env's constructor, and the noise overrides against the profiles. Their values are the env's to
check, when it is made."""

from __future__ import annotations

import inspect
from typing import Any

from clutter_gym.util.checks import short_repr


def reject_unknown(what: str, data: dict[str, Any], known: set[str]) -> None:
    unknown = sorted(set(data) - known)
    if unknown:
        raise ValueError(f"unknown {what} {short_repr(unknown)}; allowed: {sorted(known)}")


def env_arguments(env_id: str) -> list[str]:
    """The keys ``env_kwargs`` may hold for ``env_id``: its constructor's arguments, less ``render_mode`` (the
    tools set it), plus gym.make's ``max_episode_steps``."""
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    creator = load_env_creator(gym.spec(env_id).entry_point)
    return sorted({*inspect.signature(creator).parameters, "max_episode_steps"} - {"render_mode"})


def check_env_kwargs(env_id: str, noise: str, env_kwargs: Any) -> None:
    """Names and noise overrides of ``env_kwargs`` (their values are the env's to check, when it is made).

    Raises:
        ValueError: not a mapping, an unknown key (the message lists the allowed ones), or bad noise overrides.
    """
    from clutter_gym.noise.profiles import resolve_noise

    if not isinstance(env_kwargs, dict):
        raise ValueError(f"env_kwargs must be a mapping of gym.make keyword arguments, got {short_repr(env_kwargs)}")
    reject_unknown(f"env_kwargs key(s) for {env_id}", env_kwargs, set(env_arguments(env_id)))
    sections = env_kwargs.get("noise")
    if sections is None:
        return
    if not isinstance(sections, dict) or "profile" in sections:
        raise ValueError("env_kwargs.noise takes noise-section overrides such as noise.lidar.range_sigma=0.02, "
                         "applied on top of the profile (the profile is the 'noise' option), got "
                         f"{short_repr(sections)}")
    resolve_noise({"profile": noise, **sections})


def check_mix(env_id: str, mix: Any) -> None:
    if not isinstance(mix, dict) or not all(isinstance(v, list) and v for v in mix.values()):
        raise ValueError("train_env_mix must map gym.make arguments to non-empty lists of values "
                         f"({{obstacle_density: [0.05, 0.12, 0.2]}}), got {short_repr(mix)}")
    reject_unknown(f"train_env_mix key(s) for {env_id}", mix, set(env_arguments(env_id)))
    from clutter_gym.noise.profiles import PROFILE_NAMES

    if any(profile not in PROFILE_NAMES for profile in mix.get("noise", [])):
        raise ValueError(f"train_env_mix noise takes profile names, each one of {PROFILE_NAMES}, got "
                         f"{short_repr(mix['noise'])}")
