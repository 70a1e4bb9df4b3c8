"""Training configuration: typed dataclasses, loaded from ``hyperparams/ppo.yml`` and overridden from the CLI.

The YAML file holds a ``default`` block and one block per env id that overrides it key by key (``ppo`` and
``env_kwargs`` are merged one level down). Every value is checked against its field's type and range here, so a
typo in the file or on the command line fails before any env is built, naming the field.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from importlib import resources
from typing import Any

import yaml

HYPERPARAMS_FILE = "ppo.yml"
#: First evaluation seed by default: far from the seeds training starts its envs with (seed, seed + 1, ...).
EVAL_SEED = 1_000_000


@dataclass(frozen=True)
class PPOHyperparams:
    """The stable-baselines3 PPO settings this project exposes (see SB3's PPO docs for their meaning).

    ``net_arch`` is the hidden layer sizes of both the policy and the value network; ``normalize_obs`` and
    ``normalize_reward`` wrap the vector env in SB3's ``VecNormalize`` (running mean/std, clipped at 10).
    """

    learning_rate: float = 3e-4
    n_steps: int = 512
    batch_size: int = 256
    n_epochs: int = 10
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    net_arch: tuple[int, ...] = (64, 64)
    normalize_obs: bool = True
    normalize_reward: bool = True

    def __post_init__(self) -> None:
        _check_range("ppo.learning_rate", self.learning_rate, 0.0, 1.0, low_open=True)
        _check_range("ppo.n_steps", self.n_steps, 8, 1 << 20)
        _check_range("ppo.batch_size", self.batch_size, 2, 1 << 20)
        _check_range("ppo.n_epochs", self.n_epochs, 1, 100)
        _check_range("ppo.gamma", self.gamma, 0.0, 1.0, low_open=True)
        _check_range("ppo.gae_lambda", self.gae_lambda, 0.0, 1.0)
        _check_range("ppo.clip_range", self.clip_range, 0.0, 1.0, low_open=True)
        _check_range("ppo.ent_coef", self.ent_coef, 0.0, 1.0)
        _check_range("ppo.vf_coef", self.vf_coef, 0.0, 10.0)
        _check_range("ppo.max_grad_norm", self.max_grad_norm, 0.0, 100.0, low_open=True)
        if not self.net_arch or any(not isinstance(n, int) or not 1 <= n <= 4096 for n in self.net_arch):
            raise ValueError(f"ppo.net_arch must be 1 or more layer sizes in [1, 4096], got {self.net_arch!r}")

    def sb3_kwargs(self) -> dict[str, Any]:
        """Keyword arguments for ``stable_baselines3.PPO`` (normalisation is applied to the env, not here)."""
        kwargs = asdict(self)
        for key in ("net_arch", "normalize_obs", "normalize_reward"):
            kwargs.pop(key)
        kwargs["policy_kwargs"] = {"net_arch": list(self.net_arch)}
        return kwargs


@dataclass(frozen=True)
class TrainConfig:
    """Everything a training run depends on; saved as ``config.yaml`` in the run folder.

    Attributes:
        env_id: a registered clutter-gym id.
        seed: seeds PPO and the envs (env i of the vector gets ``seed + i``).
        noise: noise profile name the agent trains under.
        timesteps: total environment steps.
        n_envs: parallel envs (``SubprocVecEnv`` above 1, ``DummyVecEnv`` for 1).
        checkpoint_every: env steps between checkpoints.
        keep_checkpoints: how many of the newest checkpoints to keep.
        final_eval_episodes: episodes of the evaluation written to ``eval.json`` after training (0: none).
        env_kwargs: extra ``gym.make`` keyword arguments.
        ppo: PPO hyperparameters.
    """

    env_id: str = "ClutterNav-v0"
    seed: int = 0
    noise: str = "none"
    timesteps: int = 500_000
    n_envs: int = 4
    checkpoint_every: int = 50_000
    keep_checkpoints: int = 3
    final_eval_episodes: int = 20
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    ppo: PPOHyperparams = field(default_factory=PPOHyperparams)

    def __post_init__(self) -> None:
        from clutter_gym import ENV_IDS
        from clutter_gym.noise.profiles import PROFILE_NAMES

        if self.env_id not in ENV_IDS:
            raise ValueError(f"env_id must be one of {ENV_IDS}, got {self.env_id!r}")
        if self.noise not in PROFILE_NAMES:
            raise ValueError(f"noise must be one of {PROFILE_NAMES}, got {self.noise!r}")
        _check_range("seed", self.seed, 0, 2**31 - 1)
        _check_range("timesteps", self.timesteps, 1, 10**10)
        _check_range("n_envs", self.n_envs, 1, 256)
        _check_range("checkpoint_every", self.checkpoint_every, 1, 10**10)
        _check_range("keep_checkpoints", self.keep_checkpoints, 1, 1000)
        _check_range("final_eval_episodes", self.final_eval_episodes, 0, 100_000)
        if not isinstance(self.env_kwargs, dict) or "noise" in self.env_kwargs:
            raise ValueError("env_kwargs must be a mapping of gym.make keyword arguments without 'noise' "
                             "(the noise profile is its own option)")
        if self.ppo.batch_size > self.ppo.n_steps * self.n_envs:
            raise ValueError(f"ppo.batch_size must be in [2, n_steps * n_envs = {self.ppo.n_steps * self.n_envs}], "
                             f"got {self.ppo.batch_size}")

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["ppo"]["net_arch"] = list(self.ppo.net_arch)
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """Build from a plain mapping (a YAML block or a saved ``config.yaml``); unknown keys are errors."""
        data = dict(data)
        _reject_unknown("config", data, {f.name for f in fields(cls)})
        ppo = dict(data.pop("ppo", {}) or {})
        _reject_unknown("ppo", ppo, {f.name for f in fields(PPOHyperparams)})
        if "net_arch" in ppo:
            ppo["net_arch"] = tuple(ppo["net_arch"])
        data["env_kwargs"] = dict(data.get("env_kwargs") or {})
        return cls(**data, ppo=PPOHyperparams(**ppo))


def _check_range(name: str, value: Any, low: float, high: float, low_open: bool = False) -> None:
    number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if isinstance(low, int) and isinstance(high, int) and not isinstance(value, int):
        number = False
    if not number or not (low < value <= high if low_open else low <= value <= high):
        bracket = "(" if low_open else "["
        raise ValueError(f"{name} must be a number in {bracket}{low}, {high}], got {value!r}")


def _reject_unknown(where: str, data: dict[str, Any], known: set[str]) -> None:
    unknown = sorted(set(data) - known)
    if unknown:
        raise ValueError(f"unknown {where} key(s) {unknown}; allowed: {sorted(known)}")


def hyperparams_table() -> dict[str, Any]:
    """The parsed ``hyperparams/ppo.yml`` shipped with the package."""
    text = resources.files("clutter_gym.training").joinpath("hyperparams", HYPERPARAMS_FILE).read_text()
    return yaml.safe_load(text)


def config_for(env_id: str, overrides: dict[str, Any] | None = None) -> TrainConfig:
    """The YAML default block, then the env's block, then ``overrides`` (``ppo`` and ``env_kwargs`` merged by key)."""
    table = hyperparams_table()
    merged: dict[str, Any] = {"env_id": env_id}
    for layer in (table.get("default", {}), table.get(env_id, {}), overrides or {}):
        for key, value in layer.items():
            if key in ("ppo", "env_kwargs"):
                merged[key] = {**merged.get(key, {}), **(value or {})}
            else:
                merged[key] = value
    return TrainConfig.from_dict(merged)
