"""An env of this working tree against the same env of an earlier commit, in one process: step and reset times in
alternating blocks, the collision check alone on the same recorded states, and whether the two give the same seeded
trajectory.

Timing old and new code in separate runs compares the machine's moods as much as the code (on a shared 2-core
machine the same run's reset median moved between 4.4 and 7.4 ms). Here the commit's package is built into a
temporary folder under the name ``clutter_gym_base`` (its sources' imports renamed to match), both envs are made
with ``gym.make``, and blocks of each alternate, so that noise hits both alike; figures are medians over blocks.

    python -m benchmarks.speed.versus_commit    # ClutterNav-v1 against HEAD
    python -m benchmarks.speed.versus_commit --commit 3f62401 --env ClutterNav-v1 \
        --env-kwargs '{"subgoal_lookahead": 0.5}'

Needs git and the commit in this repository; the commit's package is copied, not installed (no build, no downloads).
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from types import ModuleType

import gymnasium as gym
import numpy as np
import tomllib

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import alternating_rounds, run_block, table_header

ROOT = Path(__file__).resolve().parents[2]
BASE = "clutter_gym_base"


def build_base(commit: str, folder: Path) -> None:
    """Put ``commit``'s package into ``folder`` as ``clutter_gym_base`` (laid out as its pyproject.toml's
    ``package-dir`` maps it, its imports renamed to match) and onto ``sys.path``."""
    source, site = folder / "source", folder / "site"
    source.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", commit], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(source)], input=archive, check=True)
    layout = tomllib.loads((source / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    for package, directory in sorted(layout.items()):  # parents before the packages inside them
        shutil.copytree(source / directory, site.joinpath(BASE, *package.split(".")[1:]), dirs_exist_ok=True)
    for path in (site / BASE).rglob("*.py"):
        path.write_text(re.sub(r"\bclutter_gym\b", BASE, path.read_text()))
    sys.path.insert(0, str(site))


def import_base(module: str) -> ModuleType:
    """``module`` of the package :func:`build_base` made (``clutter_gym_base.<module>``), imported without its env
    ids replacing this tree's: what makes envs after this makes this tree's."""
    ours = dict(gym.registry)
    with warnings.catch_warnings():  # the base package registers the same ids over ours
        warnings.simplefilter("ignore")
        imported = importlib.import_module(f"{BASE}.{module}")
    gym.registry.clear()
    gym.registry.update(ours)
    return imported


def make_pair(env_id: str, kwargs: dict) -> dict[str, gym.Env]:
    """{"base": the commit's env, "new": this tree's}, both through ``gym.make`` with the same wrappers."""
    new_spec = gym.spec(env_id)
    with warnings.catch_warnings():  # the base package registers the same ids over ours
        warnings.simplefilter("ignore")
        ours = dict(gym.registry)
        __import__(BASE)
        base_spec = gym.spec(env_id)
        gym.registry.clear()  # ours back under every id, for whatever makes envs after this
        gym.registry.update(ours)
    if not base_spec.entry_point.startswith(BASE):
        raise RuntimeError(f"the commit's package did not register {env_id}")
    return {"base": gym.make(base_spec, **kwargs), "new": gym.make(new_spec, **kwargs)}


def same_trajectory(envs: dict[str, gym.Env], steps: int, seed: int) -> str:
    """Step both envs with the same seeded random actions; "identical", or where they first differ."""
    first = {}
    for name, env in envs.items():
        rng = np.random.default_rng(seed)
        obs, _ = env.reset(seed=seed)
        record = []
        for _ in range(steps):
            obs, reward, terminated, truncated, _ = env.step(rng.uniform(-1, 1, env.action_space.shape))
            record.append((obs, reward))
            if terminated or truncated:
                obs, _ = env.reset()
        first[name] = record
    for i, ((obs_a, r_a), (obs_b, r_b)) in enumerate(zip(first["base"], first["new"])):
        keys = [k for k in obs_a if not np.array_equal(obs_a[k], obs_b[k])]
        if keys or r_a != r_b:
            return f"differ from step {i} ({', '.join(keys) or 'reward'})"
    return f"identical ({steps} steps)"


def recorded_states(envs: dict[str, gym.Env], actions: np.ndarray, seed: int) -> list:
    """The robot states of one episode of ``actions`` in the new env (both envs reset with ``seed``, so both
    checkers hold that episode's scene), for timing the two collision checkers on the same states."""
    for env in envs.values():
        env.reset(seed=seed)
    states = []
    for action in actions:
        _, _, terminated, truncated, _ = envs["new"].step(action)
        if terminated or truncated:
            break
        states.append(envs["new"].unwrapped.robot.state())
    return states


def check_block(env: gym.Env, states: list) -> float:
    """Mean seconds of the env's collision check (``checker.check``) over ``states``, swept audit included."""
    checker = env.unwrapped.checker
    t0 = time.perf_counter()
    for state in states:
        checker.check(state)
    return (time.perf_counter() - t0) / len(states)


def reset_block(env: gym.Env, n: int) -> float:
    """Median seconds of ``n`` resets."""
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        env.reset()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commit", default="HEAD", help="the commit to compare with (default: HEAD)")
    parser.add_argument("--env", default="ClutterNav-v1")
    parser.add_argument("--env-kwargs", default="{}", help="JSON keyword arguments for both envs")
    parser.add_argument("--rounds", type=int, default=12)
    parser.add_argument("--steps", type=int, default=500, help="random-action steps per step block")
    parser.add_argument("--resets", type=int, default=60, help="resets per reset block")
    parser.add_argument("--trajectory-steps", type=int, default=600, help="seeded steps compared between the two")
    args = parser.parse_args()
    kwargs = json.loads(args.env_kwargs)
    with tempfile.TemporaryDirectory() as folder:
        build_base(args.commit, Path(folder))
        envs = make_pair(args.env, kwargs)
        trajectory = same_trajectory(envs, args.trajectory_steps, seed=7)
        rng = np.random.default_rng(0)
        actions = rng.uniform(-1, 1, (args.steps, *envs["new"].action_space.shape)).astype(np.float32)
        for env in envs.values():
            env.reset(seed=1)
            reset_block(env, min(50, args.resets))  # warm-up: pools filled, kernels compiled
        steps = alternating_rounds({k: (lambda e=e: run_block(e, actions)[0] / len(actions)) for k, e in envs.items()},
                                   args.rounds)
        resets = alternating_rounds({k: (lambda e=e: reset_block(e, args.resets)) for k, e in envs.items()},
                                    args.rounds)
        states = recorded_states(envs, actions, seed=2)
        checks = alternating_rounds({k: (lambda e=e: check_block(e, states)) for k, e in envs.items()}, args.rounds)
        for env in envs.values():
            env.close()
    print(f"{args.env} {kwargs or ''}: this tree against {args.commit}, {args.rounds} alternating rounds; "
          f"seeded trajectories {trajectory}\n")
    print(table_header("figure", args.commit, "this tree", f"{args.commit} ÷ this tree, median (range)"))
    for label, figures, unit, scale in (("step", steps, "µs", 1e6), ("reset", resets, "ms", 1e3),
                                        (f"check ({len(states)} states)", checks, "µs", 1e6)):
        base, new = np.array(figures["base"]), np.array(figures["new"])
        ratio = base / new
        print(f"| {label} | {np.median(base) * scale:.1f} {unit} | {np.median(new) * scale:.1f} {unit} | "
              f"{np.median(ratio):.2f}× ({ratio.min():.2f}–{ratio.max():.2f}) |")


if __name__ == "__main__":
    main()
