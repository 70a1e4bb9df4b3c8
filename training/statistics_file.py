"""``vecnormalize.npz`` read without trusting it: the members' headers before their arrays, every value against the
run's config.yaml and its env's observation space.

The statistics decide what the policy sees, and a run folder can come from anyone. So each member's ``.npy``
header is read before its array (an archive of a few megabytes can declare an array of gigabytes), and a member
must hold what clutter-gym writes there: the settings string, and float arrays of the shapes the observation
space gives, finite, with a positive count and no negative variance. The settings must be those this run's config asked
for (``normalize_obs``, ``normalize_reward``, ``gamma``, SB3's clipping and epsilon, the normalised observation
keys): a file that says ``norm_obs: false`` for a run trained on normalised observations would make its policy act
on raw ones without a word. Every refusal is one ``ValueError`` line naming the file and the member or setting.
"""

from __future__ import annotations

import inspect
import json
import math
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecNormalize

from clutter_gym.training.config import TrainConfig

SETTINGS = ("norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma", "epsilon", "norm_obs_keys")
_MAX_SETTINGS_CHARS = 1 << 16  # the settings JSON clutter-gym writes is a few hundred characters
_STATISTICS = ("mean", "var", "count")


def float_keys(space: spaces.Space) -> list[str] | None:
    """Keys of the float Box entries of a Dict space (images stay unnormalised); None for a non-Dict space."""
    if not isinstance(space, spaces.Dict):
        return None
    return [k for k, s in space.spaces.items() if isinstance(s, spaces.Box) and np.issubdtype(s.dtype, np.floating)]


def expected_settings(config: TrainConfig, observation_space: spaces.Space) -> dict[str, Any]:
    """The settings of the ``VecNormalize`` that training on ``config`` makes (``vec_env.normalize``): the run's
    normalisation, discount and float observation keys, and SB3's defaults for the rest."""
    defaults = inspect.signature(VecNormalize.__init__).parameters
    return {"norm_obs": config.ppo.normalize_obs, "norm_reward": config.ppo.normalize_reward,
            "clip_obs": defaults["clip_obs"].default, "clip_reward": defaults["clip_reward"].default,
            "gamma": config.ppo.gamma, "epsilon": defaults["epsilon"].default,
            "norm_obs_keys": float_keys(observation_space)}


def expected_shapes(settings: dict[str, Any], observation_space: spaces.Space) -> dict[str, tuple[int, ...]]:
    """The shape of each statistic (``ret/mean``, ``obs/<key>/var``...) a file with ``settings`` holds."""
    shapes = {f"ret/{name}": () for name in _STATISTICS}
    if settings["norm_obs"]:
        if isinstance(observation_space, spaces.Dict):
            keys = settings["norm_obs_keys"] or list(observation_space.spaces)
            entries = {f"obs/{key}": observation_space.spaces[key].shape for key in keys}
        else:
            entries = {"obs": observation_space.shape}
        for prefix, shape in entries.items():
            shapes.update({f"{prefix}/mean": shape, f"{prefix}/var": shape, f"{prefix}/count": ()})
    return shapes


def read_npz(path: Path, config: TrainConfig, observation_space: spaces.Space
             ) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The settings and the statistics (by member name, ``ret/mean``...) of the ``vecnormalize.npz`` at ``path``,
    each member checked (see the module docstring) before the next is read.

    Raises:
        ValueError: one line naming ``path`` and what is wrong in it.
    """
    try:
        with zipfile.ZipFile(path) as archive:
            members = {info.filename.removesuffix(".npy"): info for info in archive.infolist()}
            if "settings" not in members:
                raise ValueError("it has no settings member")
            settings = _settings(_member(archive, members.pop("settings"), ()), config, observation_space)
            shapes = expected_shapes(settings, observation_space)
            check_names(members, shapes)
            arrays = {name: _member(archive, members[name], shape) for name, shape in shapes.items()}
        check_values(arrays)
    except (OSError, zipfile.BadZipFile, EOFError, ValueError) as exc:
        raise ValueError(f"{path}: {exc}") from None
    return settings, arrays


def check_statistics(settings: Any, arrays: dict[str, np.ndarray], config: TrainConfig,
                     observation_space: spaces.Space) -> None:
    """What :func:`read_npz` checks, for statistics already in memory (a trusted older run's pickle).

    Raises:
        ValueError: naming the setting or the statistic.
    """
    shapes = expected_shapes(check_settings(settings, config, observation_space), observation_space)
    check_names(arrays, shapes)
    for name, shape in shapes.items():
        if arrays[name].shape != shape:
            raise ValueError(f"{name} has shape {arrays[name].shape}; expected {shape}")
    check_values(arrays)


def check_names(found: Any, shapes: dict[str, tuple[int, ...]]) -> None:
    """The statistics ``found`` (names, without the settings) are those of ``shapes``; else a ``ValueError``."""
    if set(found) != set(shapes):
        raise ValueError(f"its statistics do not fit its settings and the observation space: unexpected "
                         f"{sorted(set(found) - set(shapes))[:8]}, missing {sorted(set(shapes) - set(found))[:8]}")


def check_values(arrays: dict[str, np.ndarray]) -> None:
    """Finite float statistics, counts above 0 and variances not below it; else a ``ValueError`` naming the
    statistic."""
    for name, array in arrays.items():
        if array.dtype.kind != "f" or not np.isfinite(array).all():
            raise ValueError(f"{name} must hold finite floats, got {_sample(array)}")
        if name.endswith("/count") and not array > 0:
            raise ValueError(f"{name} must be above 0 (observations seen), got {float(array)}")
        if name.endswith("/var") and (array < 0).any():
            raise ValueError(f"{name} must not be negative, got {_sample(array)}")


def check_settings(settings: Any, config: TrainConfig, observation_space: spaces.Space) -> dict[str, Any]:
    """``settings`` if they are the ones training on ``config`` writes (``norm_obs_keys`` may be None, SB3's
    "every key", where every key is a float one); else a ``ValueError`` naming the setting."""
    if not isinstance(settings, dict) or set(settings) != set(SETTINGS):
        keys = sorted(settings) if isinstance(settings, dict) else type(settings).__name__
        raise ValueError(f"settings must have the keys {sorted(SETTINGS)}, got {keys}")
    expected = expected_settings(config, observation_space)
    if settings["norm_obs_keys"] is None and isinstance(observation_space, spaces.Dict) \
            and expected["norm_obs_keys"] == list(observation_space.spaces):
        expected["norm_obs_keys"] = None
    for key, value in expected.items():
        got = settings[key]
        same = got == value and type(got) is type(value) or isinstance(value, float) and _same_float(got, value)
        if not same:
            source = {"norm_obs": "ppo.normalize_obs", "norm_reward": "ppo.normalize_reward", "gamma": "ppo.gamma"}
            why = (f"config.yaml says {source[key]}: {json.dumps(value)}" if key in source else
                   f"training writes {json.dumps(value)}")
            raise ValueError(f"settings.{key} is {json.dumps(got)[:80]}, but {why}")
    return settings


def _settings(array: np.ndarray, config: TrainConfig, observation_space: spaces.Space) -> dict[str, Any]:
    if array.dtype.kind != "U":
        raise ValueError(f"settings must be a JSON string, got an array of {array.dtype}")
    try:
        settings = json.loads(str(array))
    except ValueError:
        raise ValueError("settings is not JSON") from None
    return check_settings(settings, config, observation_space)


def _member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, shape: tuple[int, ...]) -> np.ndarray:
    """The array of one ``.npy`` member, read only once its header says it is of ``shape`` and of a plain dtype
    (the settings: a string of bounded length)."""
    name = info.filename.removesuffix(".npy")
    with archive.open(info) as f:
        version = np.lib.format.read_magic(f)
        header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        found, fortran, dtype = header(f)
        if found != shape or dtype.hasobject:
            raise ValueError(f"{name} is an array of shape {found} and dtype {dtype}; expected shape {shape}")
        if name == "settings" and dtype.itemsize > 4 * _MAX_SETTINGS_CHARS:
            raise ValueError(f"settings is a string of {dtype.itemsize // 4:,} characters, at most "
                             f"{_MAX_SETTINGS_CHARS:,} allowed")
        size = dtype.itemsize * math.prod(shape)
        data = f.read(size)
    if len(data) != size:
        raise ValueError(f"{name} is shorter than its header says")
    return np.frombuffer(data, dtype=dtype).reshape(shape, order="F" if fortran else "C").copy()


def _same_float(a: Any, b: float) -> bool:
    return isinstance(a, (int, float)) and not isinstance(a, bool) and float(a) == b


def _sample(array: np.ndarray) -> str:
    """A short view of an array for a message."""
    return np.array2string(array.ravel()[:4], threshold=4)[:80] + (" ..." if array.size > 4 else "")
