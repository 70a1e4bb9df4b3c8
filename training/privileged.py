"""Fine-tuning a distilled student with PPO: an actor that reads only the robot's sensors, a critic that may read
privileged entries too (asymmetric actor-critic), and a regulariser towards the teacher that decays.

:class:`PrivilegedCriticPolicy` is SB3's ``MultiInputPolicy`` with separate feature extractors: the actor's reads
the student's entries, the critic's those and ``critic_inputs`` (say the subgoal on the planned path, which tells
the value of a state far better than a LIDAR scan does). Its actor has the same layers, under the same names, as a
``MultiInputPolicy`` on the student's entries alone, and acting reads only them: a loaded student is given the
student's observations and nothing else (:func:`clutter_gym.training.agent.load`).

:class:`DistilledPPO` is SB3's PPO plus, after each update, passes that pull the policy's mean action towards the
teacher's action at the rollout's states (``info["teacher_action"]``, which :class:`TeacherLabels` adds), weighted
by ``bc_weight`` decaying linearly to 0 over ``bc_steps`` env steps: the student leaves the teacher's behaviour
only as far as its own return pays for.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.distributions import Distribution
from stable_baselines3.common.policies import MultiInputActorCriticPolicy
from stable_baselines3.common.preprocessing import get_flattened_obs_dim
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from clutter_gym.training.binned_actions import soft_targets
from clutter_gym.training.scan_features import SCAN_KEY, ScanFeatures


class SelectKeys(BaseFeaturesExtractor):
    """The observation entries ``keys`` flattened and concatenated, in sorted order (as SB3's CombinedExtractor
    orders a Dict's Box entries)."""

    def __init__(self, observation_space: spaces.Dict, keys: Sequence[str]) -> None:
        keys = sorted(keys)
        super().__init__(observation_space, sum(get_flattened_obs_dim(observation_space[k]) for k in keys))
        self.keys = tuple(keys)

    def forward(self, observations: dict[str, th.Tensor]) -> th.Tensor:
        return th.cat([th.flatten(observations[k], start_dim=1) for k in self.keys], dim=1)


class _TwoInputMlp(nn.Module):
    """SB3's ``MlpExtractor`` layout (``policy_net``, ``value_net``) for an actor and a critic with inputs of
    different sizes."""

    def __init__(self, actor_dim: int, critic_dim: int, net_arch: list[int], activation_fn: type[nn.Module]) -> None:
        super().__init__()

        def mlp(size: int) -> nn.Sequential:
            layers: list[nn.Module] = []
            for width in net_arch:
                layers += [nn.Linear(size, width), activation_fn()]
                size = width
            return nn.Sequential(*layers)

        self.policy_net, self.value_net = mlp(actor_dim), mlp(critic_dim)
        self.latent_dim_pi = self.latent_dim_vf = net_arch[-1] if net_arch else actor_dim
        if not net_arch:
            raise ValueError("a privileged critic needs at least one hidden layer (ppo.net_arch)")

    def forward_actor(self, features: th.Tensor) -> th.Tensor:
        return self.policy_net(features)

    def forward_critic(self, features: th.Tensor) -> th.Tensor:
        return self.value_net(features)


class PrivilegedCriticPolicy(MultiInputActorCriticPolicy):
    """An actor on every entry but ``critic_inputs``, a critic on every entry (see the module docstring).

    Args:
        critic_inputs: the observation entries only the critic reads.
        net_arch: hidden layer sizes, the same for the actor and the critic.
        scan_conv: the actor's LIDAR read by convolution layers of these widths
            (:mod:`clutter_gym.training.scan_features`); empty: flattened with the rest.
        scans: the entries the convolution reads, channels stacked (the LIDAR, and a polar scan memory).
    """

    def __init__(self, observation_space: spaces.Dict, action_space: spaces.Space, lr_schedule: Any,
                 critic_inputs: Sequence[str] = (), net_arch: list[int] | None = None,
                 scan_conv: Sequence[int] = (), scans: Sequence[str] = (SCAN_KEY,), **kwargs: Any) -> None:
        missing = sorted(set(critic_inputs) - set(observation_space.spaces))
        if missing:
            raise ValueError(f"critic_inputs {missing} are not observation entries; the env gives "
                             f"{sorted(observation_space.spaces)}")
        self.critic_inputs = tuple(sorted(critic_inputs))
        self.actor_keys = tuple(k for k in sorted(observation_space.spaces) if k not in self.critic_inputs)
        self._hidden = list(net_arch or [64, 64])
        self.scan_conv, self.scans = tuple(scan_conv), tuple(scans)
        if self.scan_conv:
            kwargs.update(features_extractor_class=ScanFeatures, features_extractor_kwargs={
                "keys": self.actor_keys, "widths": self.scan_conv, "scans": self.scans})
        else:
            kwargs.update(features_extractor_class=SelectKeys, features_extractor_kwargs={"keys": self.actor_keys})
        kwargs["share_features_extractor"] = False
        super().__init__(observation_space, action_space, lr_schedule, net_arch=self._hidden, **kwargs)

    def _build_mlp_extractor(self) -> None:
        self.vf_features_extractor = SelectKeys(self.observation_space, list(self.observation_space.spaces))
        self.mlp_extractor = _TwoInputMlp(self.pi_features_extractor.features_dim,
                                          self.vf_features_extractor.features_dim, self._hidden, self.activation_fn)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "critic_inputs": self.critic_inputs,
                "scan_conv": list(self.scan_conv), "scans": list(self.scans)}

    @property
    def actor_space(self) -> spaces.Dict:
        """The observation entries the actor reads: what a loaded student is given."""
        return spaces.Dict({key: self.observation_space[key] for key in self.actor_keys})


def imitation_loss(policy: MultiInputActorCriticPolicy, obs: dict[str, th.Tensor], labels: th.Tensor,
                   bins: int = 0) -> th.Tensor:
    """How far the policy is from the teacher's ``labels`` on a batch of observations: the squared error of its mean
    action, or for binned actions (:mod:`clutter_gym.training.binned_actions`) the cross-entropy of its bins against
    the two bins either side of each label."""
    return distribution_loss(policy.get_distribution(obs), labels, bins)


def distribution_loss(distribution: Distribution, labels: th.Tensor, bins: int = 0,
                      weights: th.Tensor | None = None) -> th.Tensor:
    """:func:`imitation_loss` of the policy's action ``distribution`` over a batch; with ``weights``, each sample's
    share of the mean in proportion to its weight."""
    if not bins:
        errors = (distribution.distribution.mean - labels) ** 2
    else:
        log_probs = th.stack([d.logits for d in distribution.distribution], dim=1)  # (batch, entries, bins)
        errors = -(soft_targets(labels, bins) * log_probs).sum(-1)
    if weights is None:
        return errors.mean()
    return (errors.mean(dim=1) * weights).sum() / weights.sum()


class LabelRecorder(BaseCallback):
    """Keeps ``info["teacher_action"]`` of every step of the current rollout, aligned with SB3's rollout buffer
    (row ``t`` of env ``i``: the teacher's action at the state the policy acted in at step ``t``)."""

    def _on_rollout_start(self) -> None:
        self.labels: list[np.ndarray] = []

    def _on_step(self) -> bool:
        self.labels.append(np.stack([info["teacher_action"] for info in self.locals["infos"]]))
        return True


class DistilledPPO(PPO):
    """PPO whose updates are followed by a decaying pull towards the teacher's actions (module docstring).

    Args:
        bc_weight: the pull's weight at ``start_step``.
        bc_steps: env steps over which it decays linearly to 0.
        start_step: the env step fine-tuning started at (the distillation's last).
        recorder: the callback that records the teacher's labels during rollouts (passed to ``learn`` too).
    """

    def __init__(self, *args: Any, bc_weight: float = 0.0, bc_steps: int = 1, start_step: int = 0,
                 recorder: LabelRecorder | None = None, action_bins: int = 0, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.bc_weight, self.bc_steps, self.start_step, self.recorder = bc_weight, bc_steps, start_step, recorder
        self.action_bins = action_bins

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "recorder"]

    def pull(self) -> float:
        """The regulariser's weight now."""
        done = max(self.num_timesteps - self.start_step, 0)
        return self.bc_weight * max(0.0, 1.0 - done / self.bc_steps)

    def train(self) -> None:
        super().train()
        weight = self.pull()
        self.logger.record("train/teacher_pull", weight)
        if weight <= 0.0 or self.recorder is None or not self.recorder.labels:
            return
        # the buffer is flat env-major after the update (SB3's swap_and_flatten): row = env * n_steps + step
        steps = np.stack(self.recorder.labels)
        labels = th.as_tensor(steps.swapaxes(0, 1).reshape(-1, steps.shape[-1]), dtype=th.float32)
        self.policy.set_training_mode(True)
        losses = []
        for _ in range(self.n_epochs):
            order = th.randperm(len(labels))  # torch's generator, which the model's seed sets
            for start in range(0, len(labels), self.batch_size):
                rows = order[start:start + self.batch_size]
                batch = self.rollout_buffer._get_samples(rows.numpy())
                loss = weight * imitation_loss(self.policy, batch.observations, labels[rows], self.action_bins)
                self.policy.optimizer.zero_grad()
                loss.backward()
                th.nn.utils.clip_grad_norm_(self.policy.parameters(), self.max_grad_norm)
                self.policy.optimizer.step()
                losses.append(float(loss.detach()))
        self.logger.record("train/teacher_loss", float(np.mean(losses)))
