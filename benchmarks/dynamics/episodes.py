"""What the reduced-dynamics benchmarks share: a scripted controller's closed-loop episodes on held-out layouts, and
envs' random-action rates in alternating blocks."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from benchmarks.harness import EnvRunner

#: held-out layouts: the seeds evaluation uses (docs/learning.md)
HELD_OUT = 1_000_000


def closed_loop(env: gym.Env, policy: Callable[[Any], np.ndarray], episodes: int) -> dict[str, float]:
    """``policy``'s episodes on the held-out layouts: success, collision episodes, the env's step time (ms, ``step``
    alone) and the share of steps its reduced model ran. Closes ``env``."""
    success = collided = steps = 0
    seconds = 0.0
    for i in range(episodes):
        obs, _ = env.reset(seed=HELD_OUT + i)
        touched = False
        while True:
            action = policy(obs)
            start = time.perf_counter()
            obs, _, terminated, truncated, info = env.step(action)
            seconds += time.perf_counter() - start
            steps += 1
            touched |= info["cost"] > 0
            if terminated or truncated:
                success += bool(info["is_success"])
                collided += touched
                break
    reduced = getattr(env.unwrapped.dynamics, "reduced_steps", 0)
    env.close()
    return {"success": success / episodes, "collisions": collided / episodes, "ms": 1e3 * seconds / steps,
            "reduced": reduced / steps}


def alternating_rates(envs: Mapping[str, gym.Env], rounds: int, steps: int) -> dict[str, float]:
    """Median steps/s (``step`` alone) over ``rounds`` alternating blocks of ``steps`` uniform-random actions per env,
    each round's actions drawn from one seed for every env."""
    runners = {name: env if isinstance(env, EnvRunner) else EnvRunner(env, seed=0) for name, env in envs.items()}
    rates: dict[str, list[float]] = {name: [] for name in runners}
    for r in range(rounds):
        for name, runner in runners.items():
            rng = np.random.default_rng(r)
            space = runner.env.action_space
            seconds, _, _ = runner.run(lambda obs, i: rng.uniform(space.low, space.high), steps)
            rates[name].append(steps / seconds)
    return {name: float(np.median(values)) for name, values in rates.items()}


def loop_cells(row: dict[str, float], physics_ms: float) -> str:
    """A :func:`closed_loop` row's cells, from success to the speed-up over full physics' step time."""
    return (f"{row['success']:.0%} | {row['collisions']:.0%} | {row['reduced']:.0%} | {row['ms']:.3f} | "
            f"{physics_ms / row['ms']:.2f}x |")


def print_versus_panda(env_id: str, rounds: int, steps: int = 1000) -> None:
    """Print :func:`versus_panda`'s rates, each model's against PandaReach-v3 where it is installed."""
    rates = versus_panda(env_id, rounds, steps)
    print(f"\n## Random actions, {rounds} alternating blocks of {steps:,} steps (median steps/s)\n")
    peer = rates.get("PandaReach-v3")
    for name, rate in rates.items():
        against = f", {rate / peer:.2f}x PandaReach-v3" if peer and name != "PandaReach-v3" else ""
        print(f"- {name}: {rate:,.0f} steps/s{against}")


def versus_panda(env_id: str, rounds: int, steps: int = 1000) -> dict[str, float]:
    """:func:`alternating_rates` of ``env_id`` under each model and of panda-gym's PandaReach-v3 (absent when panda-gym
    is not installed)."""
    from benchmarks.speed.throughput import make_peer

    envs: dict[str, Any] = {mode: gym.make(env_id, dynamics=mode) for mode in ("physics", "reduced")}
    peer = make_peer()
    if peer is not None:
        envs["PandaReach-v3"] = peer
    return alternating_rates(envs, rounds, steps)
