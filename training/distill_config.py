"""The settings of a run whose policy is distilled from a privileged teacher: ``teacher``, ``distill`` and
``critic_inputs`` in ``config.yaml`` (docs/training.md, "Teacher and student").

A run with a teacher trains in two stages. First DAgger rounds (:mod:`clutter_gym.training.distill`): the
student policy drives (the teacher drives a decaying share of the episodes), the teacher labels every state the
student visits, the labels are aggregated, and the student is fitted to all of them. Then, up to the run's
``timesteps``, PPO fine-tunes the student (:mod:`clutter_gym.training.privileged`): its critic may read
privileged observation entries (``critic_inputs``) that its actor never sees, and a regulariser towards the
teacher's action decays to nothing. ``env_kwargs`` stay the student's own: what its policy reads, and all that a
loaded student needs.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from typing import Any

from clutter_gym.training.teachers import TEACHERS, check_teacher


@dataclass(frozen=True)
class TeacherSettings:
    """Who labels the student's states.

    Attributes:
        name: a teacher of the run's env (:data:`clutter_gym.training.teachers.TEACHERS`); "" for a run without one.
        env_kwargs: env arguments the teacher reads on top of the student's ``env_kwargs`` (its map-based parts);
            empty: the teacher's own (the table in :mod:`clutter_gym.training.teachers`).
    """

    name: str = ""
    env_kwargs: dict[str, Any] = field(default_factory=dict)

    def check(self, env_id: str) -> None:
        if self.name:
            check_teacher(env_id, self.name)
        if not isinstance(self.env_kwargs, dict):
            raise ValueError(f"teacher.env_kwargs must be a mapping of gym.make arguments, got {self.env_kwargs!r}")
        if self.env_kwargs and not self.name:
            raise ValueError("teacher.env_kwargs needs teacher.name")

    def kwargs(self, env_id: str) -> dict[str, Any]:
        """The env arguments the teacher reads (its own, updated by :attr:`env_kwargs`)."""
        return {**TEACHERS[env_id][self.name], **self.env_kwargs} if self.name else {}


@dataclass(frozen=True)
class DistillSettings:
    """The DAgger rounds and the fine-tuning's pull towards the teacher.

    Attributes:
        rounds: DAgger rounds.
        round_steps: env steps per round, over all of the run's envs.
        warmup_steps: env steps driven by the teacher before the first round, to fit the observation normalisation,
            which is then frozen for the rounds (so every stored observation is normalised alike); not stored.
        teacher_share: the share of the first round's episodes the teacher drives, in [0, 1].
        share_decay: each later round's share is the one before times this, in [0, 1] (0: the student drives
            every episode after the first round).
        epochs: passes over the aggregated data set after each round.
        batch_size: samples per gradient step (a recurrent student's: ``batch_size // sequence_length`` whole
            sequences, at least one).
        sequence_length: a recurrent student's data set is cut into sequences of this many consecutive steps of one
            env, over which the fit unrolls its LSTM (:mod:`clutter_gym.training.sequences`).
        learning_rate: Adam step size of the fit.
        max_samples: the aggregated data set keeps the newest this many samples.
        bc_weight: weight, at the start of the PPO fine-tuning, of the squared distance between the policy's mean
            action and the teacher's in its loss; it decays linearly to 0 over ``bc_steps``.
        bc_steps: env steps over which ``bc_weight`` decays.
        disagreement_weight: weight in the fit of a state where the student's deterministic action was further than
            ``disagreement_threshold`` from the teacher's, against 1 for the others (1: every state alike).
        disagreement_threshold: that distance, the largest over the action's entries, in normalised units in (0, 2]
            (one bin of ``action_bins`` bins is 2 / (bins - 1)).
    """

    rounds: int = 10
    round_steps: int = 32768
    warmup_steps: int = 4096
    teacher_share: float = 1.0
    share_decay: float = 0.0
    epochs: int = 4
    batch_size: int = 512
    sequence_length: int = 128
    learning_rate: float = 1e-3
    max_samples: int = 1_000_000
    bc_weight: float = 0.0
    bc_steps: int = 200_000
    disagreement_weight: float = 1.0
    disagreement_threshold: float = 0.25

    def __post_init__(self) -> None:
        _check("distill.rounds", self.rounds, 1, 1000)
        _check("distill.round_steps", self.round_steps, 1, 10**9)
        _check("distill.warmup_steps", self.warmup_steps, 0, 10**9)
        _check("distill.teacher_share", self.teacher_share, 0.0, 1.0)
        _check("distill.share_decay", self.share_decay, 0.0, 1.0)
        _check("distill.epochs", self.epochs, 1, 1000)
        _check("distill.batch_size", self.batch_size, 1, 1 << 20)
        _check("distill.sequence_length", self.sequence_length, 1, 100_000)
        _check("distill.learning_rate", self.learning_rate, 1e-8, 1.0)
        _check("distill.max_samples", self.max_samples, 1, 10**9)
        _check("distill.bc_weight", self.bc_weight, 0.0, 1e4)
        _check("distill.bc_steps", self.bc_steps, 1, 10**10)
        _check("distill.disagreement_weight", self.disagreement_weight, 1.0, 1e3)
        _check("distill.disagreement_threshold", self.disagreement_threshold, 1e-6, 2.0)

    def share(self, round_index: int) -> float:
        """The share of the episodes the teacher drives in round ``round_index`` (0-based)."""
        return self.teacher_share * self.share_decay**round_index if round_index else self.teacher_share

    @property
    def steps(self) -> int:
        """Env steps of the whole distillation, the warm-up included."""
        return self.warmup_steps + self.rounds * self.round_steps

    @classmethod
    def from_dict(cls, data: Any) -> DistillSettings:
        if not isinstance(data, dict):
            raise ValueError(f"distill must be a mapping of settings, got {data!r}")
        unknown = sorted(set(data) - {f.name for f in fields(cls)})
        if unknown:
            raise ValueError(f"unknown distill key(s) {unknown}; allowed: {sorted(f.name for f in fields(cls))}")
        return cls(**data)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _check(name: str, value: Any, low: float, high: float) -> None:
    integer = isinstance(low, int) and isinstance(high, int)
    ok = isinstance(value, int if integer else (int, float)) and not isinstance(value, bool)
    if not ok or not math.isfinite(value) or not low <= value <= high:
        raise ValueError(f"{name} must be a{'n integer' if integer else ' number'} in [{low}, {high}], got {value!r}")
