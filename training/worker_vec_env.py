"""A vector env that steps several envs per process, one message per worker process per vector step.

SB3's ``SubprocVecEnv`` gives every env its own process and exchanges one message per env per step. On a small
machine the exchange costs about as much as a ClutterNav step, so more workers than cores only add wake-ups, and
a worker per core still waits on one message per env. Here the envs are split into contiguous blocks, one per
worker, and the first worker is this process itself: it steps its block while the worker processes step theirs,
instead of sleeping until they answer. Each worker process runs a ``DummyVecEnv`` over its block and answers a
whole batch per message. Env ``i`` is the same env, seeded the same way, whatever the number of workers: the split
changes the speed, never the trajectories.
"""

from __future__ import annotations

import multiprocessing as mp
import traceback
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv
from stable_baselines3.common.vec_env.base_vec_env import CloudpickleWrapper, VecEnvIndices, VecEnvObs, VecEnvStepReturn


class WorkerError:
    """An exception raised in a worker, sent back to be raised again in the parent with the worker's traceback."""

    def __init__(self, error: BaseException) -> None:
        self.error, self.trace = error, traceback.format_exc()


def _answer(envs: DummyVecEnv, cmd: str, data: Any) -> Any:
    if cmd == "step":
        obs, rewards, dones, infos = envs.step(data)
        return obs, rewards, dones, infos, envs.reset_infos
    if cmd == "reset":
        seed, options = data
        if seed is not None:
            envs.seed(seed)  # env k of this worker gets seed + k, as in the parent's numbering
        envs.set_options(options)
        return envs.reset(), envs.reset_infos
    if cmd == "get_attr":
        return envs.get_attr(*data)
    if cmd == "set_attr":
        return envs.set_attr(*data)
    if cmd == "env_method":
        name, args, kwargs, indices = data
        return envs.env_method(name, *args, indices=indices, **kwargs)
    if cmd == "is_wrapped":
        return envs.env_is_wrapped(*data)
    if cmd == "get_images":
        return envs.get_images()
    raise NotImplementedError(f"worker command {cmd!r}")


def _worker(remote: Any, parent_remote: Any, fns: CloudpickleWrapper) -> None:
    """Serve one ``DummyVecEnv`` over a pipe until ``close`` (or the parent goes away)."""
    parent_remote.close()
    envs = DummyVecEnv(fns.var)
    while True:
        try:
            cmd, data = remote.recv()
        except (EOFError, KeyboardInterrupt):
            break
        if cmd == "close":
            envs.close()
            remote.close()
            break
        try:
            remote.send(_answer(envs, cmd, data))
        except Exception as error:  # the env's own errors (a bad action, a missing attribute) reach the caller
            remote.send(WorkerError(error))


def _gather(remotes: Sequence[Any], local: Callable[[], Any] | None = None) -> list[Any]:
    """``local()``'s answer (when given) and then one reply from each of ``remotes``, in that order, or the first
    error: every remote's reply is read first, so that none is left in a pipe, whatever raised."""
    try:
        answers = [] if local is None else [local()]
    finally:
        replies = [remote.recv() for remote in remotes]
    for reply in replies:
        if isinstance(reply, WorkerError):
            raise reply.error from RuntimeError(f"in an env worker process:\n{reply.trace}")
    return answers + replies


def _flat(blocks: Sequence[Sequence[Any]]) -> list[Any]:
    """Per-worker lists, in env order."""
    return [item for block in blocks for item in block]


def _concat(parts: Sequence[VecEnvObs], space: spaces.Space) -> VecEnvObs:
    if isinstance(space, spaces.Dict):
        return {key: np.concatenate([p[key] for p in parts]) for key in space.spaces}  # type: ignore[index]
    return np.concatenate(parts)  # type: ignore[arg-type]


class WorkerVecEnv(VecEnv):
    """``len(env_fns)`` envs over ``workers`` workers in contiguous blocks (sizes differ by at most 1): the first
    block in this process, each other block in a worker process of its own (``workers - 1`` processes)."""

    def __init__(self, env_fns: list[Callable[[], gym.Env]], workers: int, start_method: str | None = None) -> None:
        if not 1 <= workers <= len(env_fns):
            raise ValueError(f"workers must be in [1, {len(env_fns)}] (one env at least per worker), got {workers}")
        bounds = np.linspace(0, len(env_fns), workers + 1).round().astype(int)
        self.blocks = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
        if start_method is None:
            start_method = "forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn"
        ctx = mp.get_context(start_method)
        self.remotes, self.processes = [], []
        for start, stop in self.blocks[1:]:  # started first: they build their envs while this process builds its own
            remote, work_remote = ctx.Pipe()
            args = (work_remote, remote, CloudpickleWrapper(env_fns[start:stop]))
            process = ctx.Process(target=_worker, args=args, daemon=True)  # daemon: never outlive a crashed parent
            process.start()
            work_remote.close()
            self.remotes.append(remote)
            self.processes.append(process)
        self.local = DummyVecEnv(env_fns[: self.blocks[0][1]])
        self.waiting, self.closed = False, False
        self._local_actions: np.ndarray | None = None
        super().__init__(len(env_fns), self.local.observation_space, self.local.action_space)

    def _call(self, cmd: str, data: Sequence[Any]) -> list[Any]:
        """Send worker ``k`` (``k`` >= 1) ``(cmd, data[k])``, answer ``data[0]`` here meanwhile; answers in
        worker order."""
        for remote, item in zip(self.remotes, data[1:]):
            remote.send((cmd, item))
        return _gather(self.remotes, lambda: _answer(self.local, cmd, data[0]))

    def step_async(self, actions: np.ndarray) -> None:
        for remote, (start, stop) in zip(self.remotes, self.blocks[1:]):
            remote.send(("step", actions[start:stop]))
        self._local_actions = actions[: self.blocks[0][1]]
        self.waiting = True

    def step_wait(self) -> VecEnvStepReturn:
        self.waiting = False
        results = _gather(self.remotes, lambda: _answer(self.local, "step", self._local_actions))
        obs, rewards, dones, infos, reset_infos = zip(*results)
        self.reset_infos = _flat(reset_infos)
        return _concat(obs, self.observation_space), np.concatenate(rewards), np.concatenate(dones), _flat(infos)

    def reset(self) -> VecEnvObs:
        # VecEnv.seed numbers the envs seed, seed + 1, ...: a block needs only its first seed.
        results = self._call("reset", [(self._seeds[start], self._options[start:stop]) for start, stop in self.blocks])
        obs, reset_infos = zip(*results)
        self.reset_infos = _flat(reset_infos)
        self._reset_seeds()
        self._reset_options()
        return _concat(obs, self.observation_space)

    def close(self) -> None:
        if self.closed:
            return
        if self.waiting:
            for remote in self.remotes:
                remote.recv()
        for remote in self.remotes:
            remote.send(("close", None))
        for process in self.processes:
            process.join()
        for remote in self.remotes:
            remote.close()
        self.local.close()
        self.closed = True

    def _ask(self, cmd: str, indices: VecEnvIndices, make_data: Callable[[list[int]], Any]) -> list[Any]:
        """Send ``cmd`` to the workers holding ``indices``; answers in the order of ``indices``."""
        wanted = list(self._get_indices(indices))
        by_worker: dict[int, list[int]] = {}
        for i in wanted:
            w = next(k for k, (start, stop) in enumerate(self.blocks) if start <= i < stop)
            by_worker.setdefault(w, []).append(i)
        asked = [w for w in by_worker if w > 0]
        for w in asked:
            self.remotes[w - 1].send((cmd, make_data([i - self.blocks[w][0] for i in by_worker[w]])))
        local = (lambda: _answer(self.local, cmd, make_data(by_worker[0]))) if 0 in by_worker else None
        replies = _gather([self.remotes[w - 1] for w in asked], local)
        answers: dict[int, Any] = {}
        for w, reply in zip(([0] if local else []) + asked, replies):
            members = by_worker[w]
            answers.update(zip(members, reply if reply is not None else [None] * len(members)))
        return [answers[i] for i in wanted]

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return self._ask("get_attr", indices, lambda local: (attr_name, local))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        self._ask("set_attr", indices, lambda local: (attr_name, value, local))

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        return self._ask("env_method", indices, lambda local: (method_name, method_args, method_kwargs, local))

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        return self._ask("is_wrapped", indices, lambda local: (wrapper_class, local))

    def get_images(self) -> Sequence[np.ndarray | None]:
        return _flat(self._call("get_images", [None] * len(self.blocks)))
