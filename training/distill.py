"""DAgger: a student policy that reads only the robot's sensors, distilled from a privileged teacher.

Ross, Gordon and Bagnell's DAgger (2011), on the run's own vector env and PPO model. Before the first round the
teacher drives ``warmup_steps`` steps that only fit the observation normalisation, which is then frozen, so every
stored observation is normalised alike and the saved statistics are the ones the policy was fitted under. Each
round the envs run ``round_steps`` steps: the student's deterministic policy drives (the teacher a decaying share of
the episodes, all of the first round's by default), the teacher's action at every visited state is its label
(:class:`~clutter_gym.training.teachers.TeacherLabels`), the round's samples join the aggregated data set, and the
actor is fitted to the whole set (regression of its mean action on the labels, or for binned actions the
cross-entropy of its bins: :mod:`clutter_gym.training.binned_actions`; a recurrent student's on whole sequences of
its steps: :mod:`clutter_gym.training.sequences`). A sample where the student's own action was
further than ``disagreement_threshold`` from its label may weigh more in the fit (``disagreement_weight``): the
states where the student goes wrong are few among the many where it already follows. After each round the student
is validated on held-out layouts (the best kept in ``best/``), checkpointed, and the round is a row of
``distill.csv``. A resumed run continues from its newest round's student with an empty data set, which the
remaining rounds fill from its own rollouts.
"""

from __future__ import annotations

import time
from math import nan
from typing import Any

import numpy as np
import torch as th
from stable_baselines3 import PPO
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from clutter_gym.training.binned_actions import decode
from clutter_gym.training.callbacks import BestPolicyKeeper, RunMonitor
from clutter_gym.training.config import TrainConfig
from clutter_gym.training.distill_config import DistillSettings
from clutter_gym.training.privileged import imitation_loss
from clutter_gym.training.run_dir import RunDir
from clutter_gym.training.sequences import SequenceDataset, fit_sequences


class Dataset:
    """The aggregated samples, observations as the policy sees them, the teacher's actions and each sample's weight
    in the fit; keeps the newest ``max_samples``."""

    def __init__(self, max_samples: int) -> None:
        self.max_samples = max_samples
        self._obs: list[dict[str, np.ndarray]] = []
        self._labels: list[np.ndarray] = []
        self._weights: list[np.ndarray] = []
        self.size = 0

    def add(self, obs: dict[str, np.ndarray], labels: np.ndarray, weights: np.ndarray | None = None) -> None:
        self._obs.append({key: np.array(value, dtype=np.float32) for key, value in obs.items()})
        self._labels.append(np.asarray(labels, dtype=np.float32))
        self._weights.append(np.ones(len(labels)) if weights is None else np.asarray(weights, dtype=np.float64))
        self.size += len(labels)
        while self.size - len(self._labels[0]) >= self.max_samples:
            self.size -= len(self._labels.pop(0))
            self._obs.pop(0)
            self._weights.pop(0)

    def arrays(self) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Every kept sample: observations by entry, labels (newest ``max_samples``)."""
        labels = np.concatenate(self._labels)[-self.max_samples:]
        obs = {key: np.concatenate([chunk[key] for chunk in self._obs])[-self.max_samples:] for key in self._obs[0]}
        return obs, labels

    def weights(self) -> np.ndarray:
        """Each kept sample's weight, in the order of :meth:`arrays`."""
        return np.concatenate(self._weights)[-self.max_samples:]


def disagreement(student: np.ndarray, labels: np.ndarray, threshold: float) -> np.ndarray:
    """Whether the student's action at each state is further than ``threshold`` from the teacher's in some entry
    (normalised units, so 2 / (bins - 1) is one bin)."""
    return np.abs(np.asarray(student, dtype=float) - labels).max(axis=1) > threshold


def fit(model: PPO, dataset: Dataset, settings: DistillSettings, optimizer: th.optim.Optimizer, bins: int) -> float:
    """``settings.epochs`` passes of the actor over the data set, lowering its :func:`imitation_loss`; the last
    pass's mean loss. Samples of unequal weight are drawn with replacement in proportion to their weights, as many
    a pass as the set holds."""
    obs, labels = dataset.arrays()
    weights = dataset.weights()
    draw = th.as_tensor(weights) if weights.min() != weights.max() else None
    policy = model.policy
    policy.set_training_mode(True)
    target = th.as_tensor(labels)
    inputs = {key: th.as_tensor(value) for key, value in obs.items()}
    total = 0.0
    for _ in range(settings.epochs):
        # torch's generator, which the model's seed sets
        order = th.randperm(len(target)) if draw is None else th.multinomial(draw, len(target), replacement=True)
        total = 0.0
        for start in range(0, len(target), settings.batch_size):
            rows = order[start:start + settings.batch_size]
            loss = imitation_loss(policy, {k: v[rows] for k, v in inputs.items()}, target[rows], bins)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += float(loss.detach()) * len(rows)
    policy.set_training_mode(False)
    return total / len(target)


def _normalizer(venv: VecEnv) -> VecNormalize | None:
    while not isinstance(venv, VecNormalize) and hasattr(venv, "venv"):
        venv = venv.venv
    return venv if isinstance(venv, VecNormalize) else None


class Distiller:
    """The DAgger rounds of one run (see the module docstring).

    Args:
        run: the run folder.
        config: its settings (``teacher`` and ``distill``).
        model: the PPO model (a RecurrentPPO for a recurrent student) whose actor is the student, on ``venv``.
        venv: the run's training envs, behind :class:`TeacherLabels`, normalisation and frame stack.
        progress: show a progress bar.
    """

    def __init__(self, run: RunDir, config: TrainConfig, model: OnPolicyAlgorithm, venv: VecEnv,
                 progress: bool) -> None:
        self.run, self.config, self.model, self.venv = run, config, model, venv
        self.settings = config.distill
        self.monitor = RunMonitor(run, config, progress)
        self.keeper = BestPolicyKeeper(run, config) if config.validate_episodes else None
        self.dataset: Dataset | SequenceDataset = (
            SequenceDataset(self.settings.max_samples, self.settings.sequence_length, config.ppo.lstm_hidden_size)
            if config.recurrent else Dataset(self.settings.max_samples))
        self.optimizer = th.optim.Adam(model.policy.parameters(), lr=self.settings.learning_rate)
        self._disagreed = self._visited = 0  # the last collection's states where the student disagreed, of all
        self._squared = 0.0  # the last collection's summed squared error of the student's actions against labels
        self._state: Any = None  # a recurrent student's LSTM state, carried from step to step
        self._starts = np.ones(venv.num_envs, dtype=bool)  # the envs whose episode starts at the next step

    def run_rounds(self) -> None:
        """The rounds not done yet (a resumed run's newest student continues)."""
        done = len(self.run.read_distill_rows())
        self.monitor.init_callback(self.model)
        self.monitor.on_training_start({}, {})
        if self.keeper is not None:
            self.keeper.init_callback(self.model)
            self.keeper.on_training_start({}, {})
        normalizer = _normalizer(self.venv)
        try:
            warmup = self.settings.warmup_steps if done == 0 else 0
            self.venv.env_method("set_teacher_share", 1.0 if warmup else self.settings.share(done))
            self.obs = self.venv.reset()  # after the share is set: it is drawn as each episode starts
            if warmup:
                self._collect(warmup, store=False)
            if normalizer is not None:
                normalizer.training = False  # frozen: every stored observation is normalised alike
            for index in range(done, self.settings.rounds):
                self._round(index)
            if normalizer is not None:
                normalizer.training = True  # PPO's fine-tuning updates them as PPO always does
        finally:
            self.monitor.on_training_end()
            if self.keeper is not None:
                self.keeper.on_training_end()

    def _round(self, index: int) -> None:
        t0 = time.perf_counter()
        share = self.settings.share(index)
        self.venv.env_method("set_teacher_share", share)
        episodes = self._collect(self.settings.round_steps, store=True)
        # the student's error at the states it has not been fitted on: its own actions there (deterministic)
        unseen = self._squared / (self._visited * self.venv.action_space.shape[-1]) if index else nan
        bins = self.config.action_bins
        if isinstance(self.dataset, SequenceDataset):
            loss = fit_sequences(self.model.policy, self.dataset, self.settings, self.optimizer, bins)
        else:
            loss = fit(self.model, self.dataset, self.settings, self.optimizer, bins)
        row: dict[str, float] = {"round": float(index), "step": float(self.model.num_timesteps),
                                 "samples": float(self.dataset.size), "teacher_share": share,
                                 "unseen_loss": unseen, "disagreement": self._disagreed / max(self._visited, 1),
                                 "loss": loss, **_rates(episodes)}
        if self.keeper is not None:
            self.keeper.num_timesteps = self.model.num_timesteps
            validation = self.keeper.validate()
            row.update(validation_success=validation["success"], validation_collision=validation["collision"])
        seconds = time.perf_counter() - t0
        self.run.add_training_time(seconds, self.model.num_timesteps)
        self.run.save_checkpoint(self.model, _normalizer(self.venv), self.model.num_timesteps,
                                 self.config.keep_checkpoints)
        self.run.append_distill_row({**row, "seconds": seconds})

    def _collect(self, steps: int, store: bool) -> list[dict[str, float]]:
        """Runs the envs ``steps`` env steps (rounded up to whole vector steps), the student acting; stores each
        state's observation with the teacher's label when ``store``; returns the finished episodes' statistics."""
        n = self.venv.num_envs
        bins = self.config.action_bins
        episodes: list[dict[str, float]] = []
        self._disagreed = self._visited = 0
        self._squared = 0.0
        for _ in range(-(-steps // n)):
            before = self._state
            actions, self._state = self.model.predict(self.obs, self._state, episode_start=self._starts,
                                                      deterministic=True)
            obs, _, dones, infos = self.venv.step(actions)
            if store:
                labels = np.stack([info["teacher_action"] for info in infos])
                acted = decode(actions, bins) if bins else actions
                disagreed = disagreement(acted, labels, self.settings.disagreement_threshold)
                self._disagreed += int(disagreed.sum())
                self._visited += n
                self._squared += float(((np.asarray(acted, dtype=float) - labels) ** 2).sum())
                weights = np.where(disagreed, self.settings.disagreement_weight, 1.0)
                if isinstance(self.dataset, SequenceDataset):
                    self.dataset.add(self.obs, labels, weights, self._starts, before)
                else:
                    self.dataset.add(self.obs, labels, weights)
            self.model.num_timesteps += n
            self.monitor.record(infos, self.model.num_timesteps)
            episodes += [info["episode_stats"] for info in infos if "episode_stats" in info]
            self.obs, self._starts = obs, dones
        return episodes


def _rates(episodes: list[dict[str, Any]]) -> dict[str, float]:
    """The round's episodes: how many, and their success and collision rates (NaN without any)."""
    if not episodes:
        return {"episodes": 0.0, "success": float("nan"), "collision": float("nan")}
    return {"episodes": float(len(episodes)), "success": float(np.mean([e["success"] for e in episodes])),
            "collision": float(np.mean([e["collision"] for e in episodes]))}
