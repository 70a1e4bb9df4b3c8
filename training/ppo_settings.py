"""The PPO settings of a run (``ppo`` in ``config.yaml``), and the range check every training setting uses."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from clutter_gym.util.checks import short_repr


@dataclass(frozen=True)
class PPOHyperparams:
    """The stable-baselines3 PPO settings this project exposes (SB3's PPO docs give the algorithm's details).

    Each attribute's line below is also its ``clutter-gym train --help`` text.

    Attributes:
        learning_rate: Adam step size.
        n_steps: env steps per env in each rollout (a rollout holds n_steps x n_envs steps).
        batch_size: minibatch size of the gradient steps.
        n_epochs: passes over each rollout.
        gamma: discount factor.
        gae_lambda: GAE bias/variance trade-off (1 = Monte Carlo returns).
        clip_range: PPO ratio clipping.
        ent_coef: entropy bonus weight.
        vf_coef: value loss weight.
        max_grad_norm: gradient norm clipping.
        net_arch: hidden layer sizes of both the policy and the value network.
        lstm_hidden_size: 0: a memoryless policy (SB3's PPO); n > 0: a recurrent one, sb3-contrib's
            ``RecurrentPPO`` with an LSTM of n units between the observation and the hidden layers, whose state an
            agent carries through its episode.
        scan_conv: a student's LIDAR read by 1D convolution layers of these widths along the beams' azimuth before
            the hidden layers (empty: the scan flattened with the other entries); students only.
        log_std_init: initial log standard deviation of the Gaussian actions (0: std 1, i.e. actions in [-1, 1]
            start as mostly noise).
        normalize_obs: normalise the float observation entries by running mean and std (SB3 VecNormalize).
        normalize_reward: scale rewards by the running std of the discounted return (SB3 VecNormalize).
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
    lstm_hidden_size: int = 0
    scan_conv: tuple[int, ...] = ()
    log_std_init: float = 0.0
    normalize_obs: bool = True
    normalize_reward: bool = True

    def __post_init__(self) -> None:
        check_range("ppo.learning_rate", self.learning_rate, 0.0, 1.0, low_open=True)
        check_range("ppo.n_steps", self.n_steps, 8, 1 << 20)
        check_range("ppo.batch_size", self.batch_size, 2, 1 << 20)
        check_range("ppo.n_epochs", self.n_epochs, 1, 100)
        check_range("ppo.gamma", self.gamma, 0.0, 1.0, low_open=True)
        check_range("ppo.gae_lambda", self.gae_lambda, 0.0, 1.0)
        check_range("ppo.clip_range", self.clip_range, 0.0, 1.0, low_open=True)
        check_range("ppo.ent_coef", self.ent_coef, 0.0, 1.0)
        check_range("ppo.vf_coef", self.vf_coef, 0.0, 10.0)
        check_range("ppo.max_grad_norm", self.max_grad_norm, 0.0, 100.0, low_open=True)
        check_range("ppo.log_std_init", self.log_std_init, -5.0, 2.0)
        check_range("ppo.lstm_hidden_size", self.lstm_hidden_size, 0, 4096)
        if not self.net_arch or any(not isinstance(n, int) or not 1 <= n <= 4096 for n in self.net_arch):
            raise ValueError("ppo.net_arch must be 1 or more layer sizes in [1, 4096], got "
                             f"{short_repr(self.net_arch)}")
        if len(self.scan_conv) > 8 or any(not isinstance(n, int) or not 1 <= n <= 256 for n in self.scan_conv):
            raise ValueError("ppo.scan_conv must be at most 8 layer widths in [1, 256] (empty: no convolution), got "
                             f"{short_repr(self.scan_conv)}")

    def sb3_kwargs(self) -> dict[str, Any]:
        """Keyword arguments for ``stable_baselines3.PPO`` (normalisation is applied to the env, not here)."""
        kwargs = asdict(self)
        for key in ("net_arch", "lstm_hidden_size", "scan_conv", "log_std_init", "normalize_obs", "normalize_reward"):
            kwargs.pop(key)
        kwargs["policy_kwargs"] = {"net_arch": list(self.net_arch), "log_std_init": self.log_std_init}
        if self.lstm_hidden_size:
            kwargs["policy_kwargs"]["lstm_hidden_size"] = self.lstm_hidden_size
        if self.scan_conv:
            kwargs["policy_kwargs"]["scan_conv"] = list(self.scan_conv)
        return kwargs


def check_range(name: str, value: Any, low: float, high: float, low_open: bool = False) -> None:
    """Raise naming ``name`` unless ``value`` is a number in [low, high] (``(low, high]`` when ``low_open``); an
    integer one when both bounds are integers."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if isinstance(low, int) and isinstance(high, int) and not isinstance(value, int):
        number = False
    if not number or not (low < value <= high if low_open else low <= value <= high):
        bracket = "(" if low_open else "["
        raise ValueError(f"{name} must be a number in {bracket}{low}, {high}], got {short_repr(value)}")
