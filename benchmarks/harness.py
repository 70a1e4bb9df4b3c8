"""What the timing benchmarks share: the random-walk actions, the step timers, alternating rounds, table headers.

Benchmarks compare competitors in one process, block by block in alternating rounds, so that machine noise hits
them alike; figures are medians over blocks. ``pb`` is pybullet, imported without its build banner.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import TypeVar

import gymnasium as gym
import numpy as np

from clutter_gym.datatypes import RobotState
from clutter_gym.util.quiet import quiet_c_output

with quiet_c_output():  # pybullet prints its build banner on import
    import pybullet as pb

T = TypeVar("T")

__all__ = ["EnvRunner", "alternating_rounds", "navigator_states", "pb", "run_block", "smooth_actions", "table_header"]


def smooth_actions(rng: np.random.Generator, n: int) -> np.ndarray:
    """A clipped random walk: the robot drives around and often into things, like a policy early in training."""
    steps = rng.normal(0.0, 0.25, size=(n, 2))
    out = np.empty((n, 2), dtype=np.float32)
    a = np.array([0.5, 0.0])
    for i in range(n):
        a = np.clip(a + steps[i], -1.0, 1.0)
        out[i] = a
    return out


def run_block(env, actions: np.ndarray) -> tuple[float, float]:
    """Step ``env`` through ``actions``, resetting where an episode ends; (seconds in step, seconds in reset)."""
    step_s = reset_s = 0.0
    for a in actions:
        t0 = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(a)
        t1 = time.perf_counter()
        step_s += t1 - t0
        if terminated or truncated:
            env.reset()
            reset_s += time.perf_counter() - t1
    return step_s, reset_s


class EnvRunner:
    """Steps an env with a policy, timing env.step only; records the actions and episode ends for a replay."""

    def __init__(self, env: gym.Env, seed: int) -> None:
        self.env = env
        self.obs, _ = env.reset(seed=seed)

    def run(self, choose, n: int) -> tuple[float, np.ndarray, list[int]]:
        """``n`` steps with actions ``choose(obs, i)``; returns (seconds in env.step, actions, end steps)."""
        total, actions, ends = 0.0, np.empty((n, *self.env.action_space.shape), dtype=np.float32), []
        for i in range(n):
            actions[i] = choose(self.obs, i)
            t0 = time.perf_counter()
            self.obs, _, terminated, truncated, _ = self.env.step(actions[i])
            total += time.perf_counter() - t0
            if terminated or truncated:
                ends.append(i)
                self.obs, _ = self.env.reset()
        return total, actions, ends


def navigator_states(env: gym.Env, steps: int, seed: int) -> Iterator[RobotState]:
    """Drive ClutterNav-v1 ``env`` with the scripted navigator from ``seed`` (resetting where episodes end) and
    yield the robot's state after each of ``steps`` steps: poses among clutter, as a policy meets them."""
    # imported here: clutter_gym.training imports torch, which the scripts that drive no navigator need not load
    from clutter_gym.training.baselines import PotentialFieldNavigator

    obs, _ = env.reset(seed=seed)
    navigator = PotentialFieldNavigator.for_env(env)
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(navigator(obs))
        if terminated or truncated:
            obs, _ = env.reset()
        yield env.unwrapped.robot.state()


def alternating_rounds(measures: dict[str, Callable[[], T]], rounds: int) -> dict[str, list[T]]:
    """Call every measure once per round, in order, for ``rounds`` rounds; the figures per measure (a number, or
    whatever record a measure returns)."""
    figures: dict[str, list[T]] = {name: [] for name in measures}
    for _ in range(rounds):
        for name, measure in measures.items():
            figures[name].append(measure())
    return figures


def table_header(*columns: str) -> str:
    """A markdown table's header row and the separator row under it."""
    return "| " + " | ".join(columns) + " |\n|" + "---|" * len(columns)
