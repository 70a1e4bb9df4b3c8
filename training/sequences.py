"""DAgger for a recurrent student: the aggregated data set kept as sequences, and the actor fitted on them.

A recurrent student's action depends on what it saw earlier in its episode, so its samples cannot be shuffled one
by one as a memoryless student's are (:mod:`clutter_gym.training.distill`). Each env's rollout is cut into
sequences of at most ``sequence_length`` consecutive steps of one episode (a new episode starts a new sequence),
each with the LSTM state the student held at its first step while collecting it (zeros at an episode's start), and
padded to full length. The fit unrolls the LSTM over whole sequences from those states (truncated backpropagation
through time, as sb3-contrib's RecurrentPPO trains), in batches of ``batch_size // sequence_length`` sequences;
since no episode starts inside a sequence, the LSTM runs each batch in one call. Padding weighs nothing, and a
sample the student got wrong while collecting weighs ``disagreement_weight`` (the memoryless fit draws it more
often instead: a sequence cannot be drawn in part).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch as th

from clutter_gym.training.distill_config import DistillSettings
from clutter_gym.training.privileged import distribution_loss


class SequenceDataset:
    """The aggregated samples as sequences of one env's episode, at most ``length`` steps each, padded to
    ``length``; keeps the newest ``max_samples`` samples (padding not counted).

    :meth:`add` takes one vector step at a time (a row per env). A sequence is complete when it holds ``length``
    steps or its env's next episode starts; the steps of one not yet complete are kept until it is.
    """

    def __init__(self, max_samples: int, length: int, hidden_size: int) -> None:
        self.max_samples, self.length, self.hidden_size = max_samples, length, hidden_size
        self._open: list[list[dict[str, Any]]] = []  # per env: the steps of its sequence under way
        self._sequences: list[dict[str, Any]] = []  # complete ones, padded
        self.size = 0

    def add(self, obs: dict[str, np.ndarray], labels: np.ndarray, weights: np.ndarray, starts: np.ndarray,
            state: tuple[np.ndarray, np.ndarray] | None) -> None:
        """One vector step: each env's observation, label and weight, whether its episode starts at this step, and
        the student's LSTM state (hidden, cell; each ``(layers, envs, size)``) before it acted (None: zeros)."""
        if not self._open:
            self._open = [[] for _ in labels]
        for env in range(len(labels)):
            if starts[env] and self._open[env]:
                self._close(env)
            row = {"obs": {key: np.array(value[env], np.float32) for key, value in obs.items()},  # copies
                   "label": np.array(labels[env], np.float32), "weight": np.float32(weights[env])}
            if not self._open[env]:  # a sequence's first step: the state the student starts it from
                zeros = np.zeros(self.hidden_size, np.float32)
                row["state"] = ((zeros, zeros) if starts[env] or state is None
                                else tuple(np.array(part[0, env], np.float32) for part in state))
            self._open[env].append(row)
            if len(self._open[env]) == self.length:
                self._close(env)

    def _close(self, env: int) -> None:
        steps, self._open[env] = self._open[env], []
        pad = self.length - len(steps)

        def padded(values: list[np.ndarray]) -> np.ndarray:
            array = np.stack(values)
            return np.concatenate([array, np.zeros((pad, *array.shape[1:]), array.dtype)]) if pad else array

        self._sequences.append({
            "obs": {key: padded([s["obs"][key] for s in steps]) for key in steps[0]["obs"]},
            "labels": padded([s["label"] for s in steps]),
            "weights": padded([s["weight"] for s in steps]),
            "hidden": steps[0]["state"][0], "cell": steps[0]["state"][1], "steps": len(steps)})
        self.size += len(steps)
        while self.size - self._sequences[0]["steps"] >= self.max_samples:
            self.size -= self._sequences.pop(0)["steps"]

    def arrays(self) -> dict[str, Any]:
        """Every complete sequence, stacked: ``obs`` (a dict), ``labels``, ``weights`` (sequence, step, ...; 0 for
        padding), and ``hidden``, ``cell`` (sequence, ``hidden_size``), the LSTM state each starts from."""
        sequences = self._sequences
        return {"obs": {key: np.stack([s["obs"][key] for s in sequences]) for key in sequences[0]["obs"]},
                **{name: np.stack([s[name] for s in sequences]) for name in ("labels", "weights", "hidden", "cell")}}


def fit_sequences(policy: Any, dataset: SequenceDataset, settings: DistillSettings, optimizer: th.optim.Optimizer,
                  bins: int) -> float:
    """``settings.epochs`` passes of the recurrent actor (sb3-contrib's ``RecurrentActorCriticPolicy``) over the
    data set's sequences in shuffled batches, lowering the weighted imitation loss; the last pass's mean loss over
    the batches (NaN before the first sequence is complete)."""
    if not dataset.size:
        return float("nan")
    data = dataset.arrays()
    obs = {key: th.as_tensor(value) for key, value in data["obs"].items()}
    labels, weights, hidden, cell = (th.as_tensor(data[name]) for name in ("labels", "weights", "hidden", "cell"))
    per_batch = max(1, settings.batch_size // dataset.length)
    no_starts = th.zeros(per_batch * dataset.length)  # every sequence's first state is given: none starts inside
    policy.set_training_mode(True)
    total = 0.0
    for _ in range(settings.epochs):
        order = th.randperm(len(labels))  # torch's generator, which the model's seed sets
        total = 0.0
        for first in range(0, len(labels), per_batch):
            rows = order[first:first + per_batch]
            flat = {key: value[rows].flatten(0, 1) for key, value in obs.items()}  # sequence-major, as sb3-contrib
            distribution, _ = policy.get_distribution(flat, (hidden[rows][None], cell[rows][None]),
                                                      no_starts[:len(rows) * dataset.length])
            loss = distribution_loss(distribution, labels[rows].flatten(0, 1), bins, weights[rows].flatten())
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += float(loss.detach()) * len(rows)
    policy.set_training_mode(False)
    return total / len(labels)
