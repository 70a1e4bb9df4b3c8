"""SB3's ``VecNormalize`` statistics in a file that cannot run code: ``vecnormalize.npz``.

SB3 saves a ``VecNormalize`` with pickle, and loading a pickle runs whatever its author put in it. A run folder
travels between people, so clutter-gym writes the statistics (running mean, variance and count of each normalised
observation entry and of the discounted return) and the wrapper's settings as plain arrays and read them back with
``allow_pickle=False``. Runs written before this kept ``vecnormalize.pkl``; those are read only when the caller
says it trusts them (``trust_pickle``), as pickles from someone else can run code on this machine.
"""

from __future__ import annotations

import json
import pickle
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.running_mean_std import RunningMeanStd
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from clutter_gym.training.config import TrainConfig
from clutter_gym.training.statistics_file import SETTINGS, check_statistics, read_npz
from clutter_gym.util.atomic import atomic_path

NORMALIZER_FILE = "vecnormalize.npz"
LEGACY_NORMALIZER_FILE = "vecnormalize.pkl"


class UntrustedFileError(ValueError):
    """A file that only pickle can read, which the caller did not say it trusts."""


def save_normalizer(normalizer: VecNormalize, path: Path) -> None:
    """The statistics and settings of ``normalizer`` as arrays in ``path`` (an ``.npz`` file, written atomically)."""
    arrays = {"settings": np.array(json.dumps({key: getattr(normalizer, key) for key in SETTINGS})),
              **_statistics(normalizer)}
    with atomic_path(path) as tmp, tmp.open("wb") as f:  # a file object: savez adds ".npz" to a bare path
        np.savez(f, **arrays)


def normalizer_path(folder: Path, trust_pickle: bool = False) -> Path | None:
    """The statistics file in a model folder: ``vecnormalize.npz``, or an older run's ``vecnormalize.pkl`` when
    ``trust_pickle``; None when the folder holds neither.

    Raises:
        UntrustedFileError: the folder holds only a pickle and ``trust_pickle`` is False.
    """
    if (folder / NORMALIZER_FILE).is_file():
        return folder / NORMALIZER_FILE
    legacy = folder / LEGACY_NORMALIZER_FILE
    if not legacy.is_file():
        return None
    if not trust_pickle:
        raise UntrustedFileError(
            f"{legacy} is a pickle (written by clutter-gym 0.1), and loading a pickle can run any code its author "
            f"put in it; if you trust where this run came from, pass --trust-pickle (trust_pickle=True in Python), "
            f"which also rewrites it as {NORMALIZER_FILE} beside it")
    return legacy


def wrap(venv: VecEnv, path: Path, config: TrainConfig) -> VecNormalize:
    """``venv`` behind a ``VecNormalize`` that continues from the statistics in ``path`` (to resume the training of
    ``config``).

    Raises:
        ValueError: the statistics are not those of a run of ``config`` on ``venv``'s observations.
    """
    settings, rms = read_statistics(path, config, venv.observation_space)
    normalizer = VecNormalize(venv, **settings)
    _restore(normalizer, rms)
    return normalizer


def detached(path: Path, config: TrainConfig, observation_space: spaces.Space,
             action_space: spaces.Space) -> VecNormalize:
    """A ``VecNormalize`` with the statistics in ``path`` and no env, for ``normalize_obs`` on single observations
    of ``observation_space`` (the env's, not a frame stack's) in a run of ``config``.

    It is restored through SB3's own unpickling hook (``__setstate__``, which leaves out the env) with state built
    from the arrays, so the normalisation is SB3's to the bit and nothing is unpickled.

    Raises:
        ValueError: the statistics are not those of a run of ``config`` on ``observation_space``.
    """
    settings, rms = read_statistics(path, config, observation_space)
    normalizer = VecNormalize.__new__(VecNormalize)
    obs_spaces = observation_space.spaces if isinstance(observation_space, spaces.Dict) else None
    normalizer.__setstate__({
        **settings, "training": False, "observation_space": observation_space, "action_space": action_space,
        "obs_spaces": obs_spaces, "num_envs": 1, "render_mode": None, "old_reward": np.array([]),
        "ret_rms": RunningMeanStd(shape=()), "obs_rms": None,
    })
    _restore(normalizer, rms)
    return normalizer


def _from_pickle(path: Path, config: TrainConfig, observation_space: spaces.Space
                 ) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The settings and statistics of an older run's trusted ``vecnormalize.pkl``, checked as a ``.npz``'s are;
    once they pass, they are also written as ``vecnormalize.npz`` beside it (when the folder is writable), so the
    next load needs no trust."""
    with path.open("rb") as f:
        normalizer = pickle.load(f)  # the caller trusts this file (normalizer_path(trust_pickle=True))
    normalizer.norm_obs_keys = getattr(normalizer, "norm_obs_keys", None)  # pickles of SB3 < 1.7 lack it
    settings, arrays = {key: getattr(normalizer, key) for key in SETTINGS}, _statistics(normalizer)
    try:
        check_statistics(settings, arrays, config, observation_space)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    try:
        save_normalizer(normalizer, path.with_name(NORMALIZER_FILE))
    except OSError:
        pass  # a read-only run folder: the statistics are read from the pickle again next time
    return settings, arrays


def _statistics(normalizer: VecNormalize) -> dict[str, np.ndarray]:
    """The running mean, variance and count of the return and of each normalised observation entry, by name
    (``ret/mean``, ``obs/var`` or ``obs/<key>/count``...)."""
    entries = {"ret": normalizer.ret_rms}
    if normalizer.norm_obs:
        obs = normalizer.obs_rms
        entries.update({f"obs/{key}": rms for key, rms in obs.items()} if isinstance(obs, dict) else {"obs": obs})
    return {f"{prefix}/{name}": np.asarray(getattr(rms, name))
            for prefix, rms in entries.items() for name in ("mean", "var", "count")}


def read_statistics(path: Path, config: TrainConfig, observation_space: spaces.Space
                    ) -> tuple[dict[str, Any], dict[str, RunningMeanStd]]:
    """The settings and the running statistics by prefix (``ret``, ``obs`` or ``obs/<key>``) in ``path``, checked
    against the run's ``config`` and its env's ``observation_space`` (one observation, not a frame stack).

    Raises:
        ValueError: one line naming ``path`` and the setting or statistic that is not what a run of ``config``
            writes (a file that is no statistics file, a shape the observation space does not give, a NaN...).
    """
    if path.suffix == ".pkl":
        settings, arrays = _from_pickle(path, config, observation_space)
    else:
        settings, arrays = read_npz(path, config, observation_space)
    rms = {}
    for prefix in {name.rsplit("/", 1)[0] for name in arrays}:
        stats = RunningMeanStd(shape=arrays[f"{prefix}/mean"].shape)
        stats.mean = arrays[f"{prefix}/mean"].astype(np.float64)
        stats.var = arrays[f"{prefix}/var"].astype(np.float64)
        stats.count = float(arrays[f"{prefix}/count"])
        rms[prefix] = stats
    return settings, rms


def _restore(normalizer: VecNormalize, rms: dict[str, RunningMeanStd]) -> None:
    """Put the checked statistics ``rms`` into ``normalizer``, whose settings came from the same file."""
    normalizer.ret_rms = rms["ret"]
    if not normalizer.norm_obs:
        return
    if isinstance(normalizer.observation_space, spaces.Dict):
        keys = normalizer.norm_obs_keys or list(normalizer.observation_space.spaces)
        normalizer.obs_rms = {key: rms[f"obs/{key}"] for key in keys}
    else:
        normalizer.obs_rms = rms["obs"]
