"""The recurrent policy: sb3-contrib's LSTM actor-critic, with the hidden layers reading the current observation's
features beside the LSTM's output.

sb3-contrib's ``RecurrentActorCriticPolicy`` puts the LSTM between the features and the hidden layers, so the
current observation reaches them only through the LSTM's state. Fitted to a teacher's labels, that student matched
its training data less well and held-out episodes worse than a memoryless one (docs/learning.md, "A recurrent
student"): what it must react to now had to pass through the memory. Here the hidden layers read both, the LSTM
free to carry only what the observation no longer shows. Everything else (the LSTM's states, episode starts,
saving and loading) is sb3-contrib's.
"""

from __future__ import annotations

import torch as th
from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy, RecurrentMultiInputActorCriticPolicy
from stable_baselines3.common.torch_layers import MlpExtractor
from torch import nn


class _LstmBeside:
    """The two changes to sb3-contrib's recurrent policy (module docstring)."""

    lstm_output_dim: int
    features_dim: int

    def _build_mlp_extractor(self) -> None:
        self.mlp_extractor = MlpExtractor(self.lstm_output_dim + self.features_dim, net_arch=self.net_arch,
                                          activation_fn=self.activation_fn, device=self.device)

    @staticmethod
    def _process_sequence(features: th.Tensor, lstm_states: tuple[th.Tensor, th.Tensor], episode_starts: th.Tensor,
                          lstm: nn.LSTM) -> tuple[th.Tensor, tuple[th.Tensor, th.Tensor]]:
        output, states = RecurrentActorCriticPolicy._process_sequence(features, lstm_states, episode_starts, lstm)
        return th.cat([output, features], dim=1), states


class LstmBesidePolicy(_LstmBeside, RecurrentActorCriticPolicy):
    """For a Box observation."""


class MultiInputLstmBesidePolicy(_LstmBeside, RecurrentMultiInputActorCriticPolicy):
    """For a Dict observation."""


def recurrent_policy(dict_observations: bool) -> type[RecurrentActorCriticPolicy]:
    """The recurrent policy class for Dict observations or a Box."""
    return MultiInputLstmBesidePolicy if dict_observations else LstmBesidePolicy
