"""Samples per second of the main job's ClutterNav-v1 envs: one env alone against vector envs over worker processes.

Target (issue 12): two workers step at least 1.8x one env alone on a 2-core machine. Every configuration
steps the main job's env settings (subgoal, terminate on collision; ``--bare``: the env's defaults) with random-walk
actions, so that episodes end and reset as often as early in training. Two free-running processes, one env each,
show what two cores can give at most; the vector envs step in lockstep (every vector step waits for every worker).
``WorkerVecEnv`` (the training tooling's) and the envs' own vector env, ``gym.make_vec``'s default for them
(``clutter_gym.vector.BlockVectorEnv``), step one block of envs in this process and the other in one worker
process; Gymnasium's ``AsyncVectorEnv`` gives every env a process of its own.
Configurations run in alternating rounds (machine noise hits them alike); figures are medians over rounds. The
last line is the training loop itself: PPO with the main job's settings (rollouts, updates, observation
normalisation), in samples per second of wall time. With ``--commit`` the commit's two vector envs (its package
copied as ``benchmarks.speed.versus_commit`` copies it) step the same envs in the same rounds: the vector env's
own cost, before and after, as a ratio on the same machine at the same time (``--vector-only`` leaves out SB3's and
Gymnasium's vector envs and the training loop).

    python -m benchmarks.speed.vec_throughput [--rounds 3] [--steps 2000] [--ppo-steps 16384] [--bare]
    python -m benchmarks.speed.vec_throughput --commit main --vector-only --rounds 5
"""

from __future__ import annotations

import argparse
import functools
import multiprocessing as mp
import os
import statistics
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.vec_env import SubprocVecEnv, VecEnv

from benchmarks.harness import alternating_rounds, smooth_actions, table_header
from benchmarks.speed.versus_commit import build_base, import_base
from clutter_gym.training.config import config_for
from clutter_gym.training.train import build_model
from clutter_gym.training.vec_env import env_workers, make_env, training_env
from clutter_gym.training.worker_vec_env import WorkerVecEnv


def one_env(factory, steps: int, seed: int) -> float:
    env, walk = factory(), smooth_actions(np.random.default_rng(seed), steps)
    env.reset(seed=seed)
    t0 = time.perf_counter()
    for action in walk:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    rate = steps / (time.perf_counter() - t0)
    env.close()
    return rate


def _one_env_into(queue, factory, steps: int, seed: int) -> None:
    queue.put(one_env(factory, steps, seed))


def free_running(factory, steps: int, seed: int) -> float:
    """Two processes, one env each, never waiting for each other: the most two cores can give."""
    ctx = mp.get_context("forkserver")
    queue = ctx.Queue()
    processes = [ctx.Process(target=_one_env_into, args=(queue, factory, steps // 2, seed + k)) for k in range(2)]
    for p in processes:
        p.start()
    rates = [queue.get() for _ in processes]
    for p in processes:
        p.join()
    return sum(rates)


def vector(venv: VecEnv | gym.vector.VectorEnv, steps: int, seed: int) -> float:
    """Samples/s of ``venv`` (SB3's or Gymnasium's) over about ``steps`` samples (the vector's start-up and first
    reset untimed)."""
    vector_steps = max(1, steps // venv.num_envs)
    rng = np.random.default_rng(seed)
    walks = np.stack([smooth_actions(rng, vector_steps) for _ in range(venv.num_envs)], axis=1).astype(np.float32)
    if isinstance(venv, VecEnv):
        venv.seed(seed)
        venv.reset()
    else:
        venv.reset(seed=seed)
    t0 = time.perf_counter()
    for actions in walks:
        venv.step(actions)
    rate = vector_steps * venv.num_envs / (time.perf_counter() - t0)
    venv.close()
    return rate


def training_loop(samples: int, seed: int) -> tuple[float, int, int]:
    """Samples/s of PPO.learn with the main job's settings; returns (rate, n_envs, env workers)."""
    torch.set_num_threads(1)  # as train() does
    config = config_for("ClutterNav-v1", {"seed": seed})
    venv = training_env(config, seed=seed)
    model = build_model(config, venv)
    t0 = time.perf_counter()
    model.learn(total_timesteps=samples)
    rate = model.num_timesteps / (time.perf_counter() - t0)
    venv.close()
    return rate, config.n_envs, env_workers(config)


def measure(args: argparse.Namespace, folder: Path) -> dict[str, list[float]]:
    """The samples/s of each configuration in each round (the commit's package, if any, built in ``folder``)."""
    config = config_for("ClutterNav-v1", {})
    factory = functools.partial(make_env, config.env_id, {} if args.bare else config.make_kwargs())
    kwargs = {} if args.bare else config.make_kwargs()
    configurations = {"one env, one process": lambda: one_env(factory, args.steps, args.seed)}
    if not args.vector_only:
        configurations.update({
            "two processes, one env each, free-running (the ceiling)": lambda: free_running(factory, args.steps,
                                                                                          args.seed),
            "SB3 SubprocVecEnv, 2 envs (a process each)": lambda: vector(SubprocVecEnv([factory] * 2), args.steps,
                                                                        args.seed),
            "SB3 SubprocVecEnv, 8 envs (a process each)": lambda: vector(SubprocVecEnv([factory] * 8), args.steps,
                                                                        args.seed),
            "Gymnasium AsyncVectorEnv, 2 envs (a process each)": lambda: vector(
                gym.make_vec(config.env_id, num_envs=2, vectorization_mode="async", **kwargs), args.steps, args.seed),
        })
    worker_envs = {"": WorkerVecEnv}
    block_envs = {"": functools.partial(gym.make_vec, config.env_id, workers=2, **kwargs)}
    if args.commit:
        build_base(args.commit, folder)  # the commit's vector envs, stepping this tree's envs
        worker_envs[f" ({args.commit})"] = import_base("training.worker_vec_env").WorkerVecEnv
        block_envs[f" ({args.commit})"] = functools.partial(import_base("vector").BlockVectorEnv, config.env_id,
                                                           workers=2, **kwargs)
    for per_worker in (1, 4, 8, 16):
        for tag, make in worker_envs.items():
            configurations[f"WorkerVecEnv{tag}, 2 workers (this process + 1) x {per_worker} envs"] = functools.partial(
                lambda k, make: vector(make([factory] * (2 * k), workers=2), args.steps, args.seed), per_worker, make)
        for tag, make in block_envs.items():
            configurations[f"gym.make_vec default (BlockVectorEnv){tag}, 2 workers x {per_worker} envs"] = \
                functools.partial(lambda k, make: vector(make(num_envs=2 * k), args.steps, args.seed), per_worker, make)
    return alternating_rounds(configurations, args.rounds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=2000, help="samples per configuration per round")
    parser.add_argument("--ppo-steps", type=int, default=16384, help="samples of the training-loop measurement")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--bare", action="store_true", help="step ClutterNav-v1's defaults, not the main job's")
    parser.add_argument("--commit", default=None, help="also step this commit's WorkerVecEnv and BlockVectorEnv")
    parser.add_argument("--vector-only", action="store_true",
                        help="only one env and the two vector envs of clutter-gym (and the commit's)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        rates = measure(args, Path(folder))
    base = statistics.median(rates["one env, one process"])
    settings = "its default settings" if args.bare else "the main job's env settings"
    print(f"ClutterNav-v1 with {settings}, {os.cpu_count()} cores, random-walk actions, "
          f"{args.steps} samples per configuration, median of {args.rounds} alternating rounds\n")
    print(table_header("configuration", "samples/s", "vs one env"))
    for name, values in rates.items():
        median = statistics.median(values)
        print(f"| {name} | {median:,.0f} | {median / base:.2f}x |", flush=True)
    if args.commit:
        print(f"\n{table_header('vector env', f'this tree ÷ {args.commit}, median of the rounds (range)')}")
        for name, values in rates.items():
            if f" ({args.commit})" in name:
                ours = name.replace(f" ({args.commit})", "")
                ratio = np.array(rates[ours]) / np.array(values)  # round by round: the same machine's mood
                print(f"| {ours} | {np.median(ratio):.3f} ({ratio.min():.3f}-{ratio.max():.3f}) |")
    if args.vector_only:
        return
    rate, n_envs, workers = training_loop(args.ppo_steps, args.seed)
    print(f"| training loop: PPO, main job settings ({n_envs} envs over {workers} workers), "
          f"{args.ppo_steps:,} samples | {rate:,.0f} | {rate / base:.2f}x |")


if __name__ == "__main__":
    main()
