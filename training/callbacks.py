"""The training loop's side work: episode log, TensorBoard scalars, checkpoints, the progress bar, and the
validations that keep the best policy."""

from __future__ import annotations

import csv
import math
import time
from collections import deque

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from tqdm import tqdm

from clutter_gym.training.config import TrainConfig
from clutter_gym.training.run_dir import RunDir, writing

WINDOW = 100  # episodes in the running success / collision rates


class RunMonitor(BaseCallback):
    """Writes every finished episode to ``episodes.csv``, logs running means, checkpoints on schedule.

    Scalars under ``clutter/`` (TensorBoard): ``success_rate``, ``collision_rate``, ``cost``, ``min_clearance``,
    ``return`` and ``term_<name>`` for each reward term, means over the last 100 episodes.
    """

    def __init__(self, run: RunDir, config: TrainConfig, progress: bool) -> None:
        super().__init__()
        self.run, self.config, self.progress = run, config, progress
        self.recent: deque[dict[str, float]] = deque(maxlen=WINDOW)
        self._bar: tqdm | None = None
        self._file = None
        self._writer: csv.DictWriter | None = None

    def _on_training_start(self) -> None:
        every = self.config.checkpoint_every
        self._next_checkpoint = (self.num_timesteps // every + 1) * every
        self._start_steps, self._start_time = self.num_timesteps, time.perf_counter()
        self._calls = 0
        self.recent.extend(self.run.read_episodes()[-WINDOW:])
        if self.progress:
            self._bar = tqdm(total=self._last_step(), initial=self.num_timesteps, unit="step", dynamic_ncols=True,
                             desc=f"{self.config.env_id} seed {self.config.seed}")

    def _last_step(self) -> int:
        """The step training ends at: PPO collects whole rollouts (``n_steps`` per env), so it stops at the first
        rollout's end at or past the budget (20,480 for a budget of 20,000 in rollouts of 128 x 16)."""
        rollout = getattr(self.model, "n_steps", 1) * self.model.n_envs
        start = self.num_timesteps
        return start + math.ceil(max(self.config.timesteps - start, 0) / rollout) * rollout

    def _append(self, row: dict[str, float]) -> None:
        with writing(self.run.episodes_file):
            self._write(row)

    def _write(self, row: dict[str, float]) -> None:
        if self._writer is None:
            exists = self.run.episodes_file.is_file() and self.run.episodes_file.stat().st_size > 0
            if exists:
                with self.run.episodes_file.open(newline="") as f:
                    fieldnames = next(csv.reader(f))
            else:
                fieldnames = list(row)
            self._file = self.run.episodes_file.open("a", newline="")
            self._writer = csv.DictWriter(self._file, fieldnames=fieldnames, extrasaction="ignore")
            if not exists:
                self._writer.writeheader()
        self._writer.writerow(row)
        self._file.flush()

    def _on_step(self) -> bool:
        self.record(self.locals["infos"], self.num_timesteps)
        if self.num_timesteps >= self._next_checkpoint:
            self.run.save_checkpoint(self.model, self.model.get_vec_normalize_env(), self.num_timesteps,
                                     self.config.keep_checkpoints)
            self._next_checkpoint += self.config.checkpoint_every
        return True

    def record(self, infos: list[dict], step: int) -> None:
        """Log the episodes that ended in a vector step (reaching env step ``step``) and move the bar (the
        distillation's rounds call this too)."""
        for info in infos:
            stats = info.get("episode_stats")
            if stats is not None:
                row = {"timestep": float(step), **stats}
                self._append(row)
                self.recent.append(row)
        if self._bar is not None:
            self._bar.update(step - self._bar.n)
            self._calls += 1
            if self._calls % 50 == 0:
                self._bar.set_postfix(self._postfix(), refresh=False)

    def _postfix(self) -> dict[str, str]:
        elapsed = time.perf_counter() - self._start_time
        postfix = {"steps/s": f"{(self.num_timesteps - self._start_steps) / max(elapsed, 1e-9):.0f}"}
        if self.recent:
            postfix["success"] = f"{np.mean([r['success'] for r in self.recent]):.0%}"
            postfix["collision"] = f"{np.mean([r['collision'] for r in self.recent]):.0%}"
        return postfix

    def _on_rollout_end(self) -> None:
        if not self.recent:
            return
        for key in self.recent[-1]:
            if key != "timestep":
                name = {"success": "success_rate", "collision": "collision_rate"}.get(key, key)
                self.logger.record(f"clutter/{name}", float(np.mean([r.get(key, np.nan) for r in self.recent])))

    def _on_training_end(self) -> None:
        if self._file is not None:
            self._file.close()
        if self._bar is not None:
            self._bar.set_postfix(self._postfix())
            self._bar.close()


class BestPolicyKeeper(BaseCallback):
    """Every ``validate_every`` env steps, runs the current policy on held-out layouts and keeps the best in
    ``best/``.

    A validation is ``validate_episodes`` deterministic episodes, reset with seeds ``VALIDATION_SEED + i``: the
    same layouts every time, so validations compare policies, never scenes. Score: success rate minus collision
    rate (a policy that reaches the goal by crashing less wins). A later policy that ties the best replaces it: a
    few dozen episodes saturate once the agent is good, and of two policies with the same validation score the
    one trained longer is the better bet.
    Each validation is a row of ``validation.csv`` and TensorBoard scalars under ``validation/``.
    """

    def __init__(self, run: RunDir, config: TrainConfig) -> None:
        super().__init__()
        self.run, self.config = run, config
        self._env = None

    def _on_training_start(self) -> None:
        every = self.config.validate_every
        self._next = (self.num_timesteps // every + 1) * every
        kept = [r for r in self.run.read_validations() if r["best"]]
        self.best_score = max((r["success"] - r["collision"] for r in kept), default=-math.inf)

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            self._next += self.config.validate_every
            self.validate()
        return True

    def validate(self) -> dict[str, float]:
        """One validation of the current policy; saves it to ``best/`` if it scores at least the best so far."""
        import gymnasium as gym

        from clutter_gym.training.agent import Agent
        from clutter_gym.training.config import VALIDATION_SEED
        from clutter_gym.training.evaluate import rollouts

        if self._env is None:
            self._env = gym.make(self.config.env_id, **self.config.make_kwargs())
        normalizer = self.model.get_vec_normalize_env()
        agent = Agent(self.run, self.config, self.model, normalizer, folder=None)  # the policy as load() will see it
        rows = rollouts(self._env, agent.predict, self.config.validate_episodes, VALIDATION_SEED)
        success = float(np.mean([r["success"] for r in rows]))
        collision = float(np.mean([r["collision"] for r in rows]))
        best = success - collision >= self.best_score
        if best:
            self.best_score = success - collision
            self.run.save_model(self.model, normalizer, self.run.best_dir)
        row = {"step": float(self.num_timesteps), "success": success, "collision": collision, "best": float(best)}
        self.run.append_validation(row)
        self.logger.record("validation/success_rate", success)
        self.logger.record("validation/collision_rate", collision)
        return row

    def _on_training_end(self) -> None:
        if self._env is not None:
            self._env.close()
            self._env = None
