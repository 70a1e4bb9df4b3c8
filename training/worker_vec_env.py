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

import functools
import signal
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv
from stable_baselines3.common.vec_env.base_vec_env import CloudpickleWrapper, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from clutter_gym.util.workers import DEFAULT_TIMEOUT, Workers, blocks, check_actions, serve


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


def _serve(remote: Any, parent_remote: Any, make: CloudpickleWrapper) -> None:
    # Ctrl-C reaches every process of the terminal's group: the parent handles it (training writes a checkpoint)
    # and then closes the workers, which must still answer the step they are in, not die with a traceback.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    serve(remote, parent_remote, make.var, _answer)


def _flat(blocks: Sequence[Sequence[Any]]) -> list[Any]:
    """Per-worker lists, in env order."""
    return [item for block in blocks for item in block]


def _concat(parts: Sequence[VecEnvObs], space: spaces.Space) -> VecEnvObs:
    if isinstance(space, spaces.Dict):
        return {key: np.concatenate([p[key] for p in parts]) for key in space.spaces}  # type: ignore[index]
    return np.concatenate(parts)  # type: ignore[arg-type]


class WorkerVecEnv(VecEnv):
    """``len(env_fns)`` envs over ``workers`` workers in contiguous blocks (sizes differ by at most 1): the first
    block in this process, each other block in a worker process of its own (``workers - 1`` processes), started in
    :func:`clutter_gym.util.workers.context`. A worker that dies or gives no answer within ``worker_timeout`` seconds
    (None: no limit) raises :class:`~clutter_gym.util.workers.WorkerLostError` naming it, and ``close`` ends and
    reaps the workers whatever their state."""

    def __init__(self, env_fns: list[Callable[[], gym.Env]], workers: int, start_method: str | None = None,
                 worker_timeout: float | None = DEFAULT_TIMEOUT) -> None:
        self.blocks = blocks(len(env_fns), workers)
        # started first: they build their envs while this process builds its own
        makes = [(CloudpickleWrapper(functools.partial(DummyVecEnv, env_fns[start:stop])),)
                 for start, stop in self.blocks[1:]]
        self.workers = Workers(_serve, makes, self.blocks[1:], start_method, worker_timeout)
        try:
            self.local = DummyVecEnv(env_fns[: self.blocks[0][1]])
        except BaseException:
            self.workers.close(grace=0.0)
            raise
        self.processes = self.workers.processes
        self.closed = False
        self._local_actions: np.ndarray | None = None
        super().__init__(len(env_fns), self.local.observation_space, self.local.action_space)

    def _call(self, cmd: str, data: Sequence[Any]) -> list[Any]:
        """Send worker ``k`` (``k`` >= 1) ``(cmd, data[k])``, answer ``data[0]`` here meanwhile; answers in
        worker order."""
        for k, item in enumerate(data[1:]):
            self.workers.send(k, cmd, item)
        return self.workers.receive(range(len(data) - 1), lambda: _answer(self.local, cmd, data[0]))

    def step_async(self, actions: np.ndarray) -> None:
        actions = check_actions(actions, (self.num_envs, *self.action_space.shape))
        for k, (start, stop) in enumerate(self.blocks[1:]):
            self.workers.send(k, "step", actions[start:stop])
        self._local_actions = actions[: self.blocks[0][1]]

    def step_wait(self) -> VecEnvStepReturn:
        results = self.workers.receive(range(len(self.blocks) - 1),
                                       lambda: _answer(self.local, "step", self._local_actions))
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
        """Close the envs here and in the workers, and end the workers (those that died or hang too)."""
        if self.closed:
            return
        try:
            self.workers.close()
        finally:
            self.closed = True
            self.local.close()

    def _ask(self, cmd: str, indices: VecEnvIndices, make_data: Callable[[list[int]], Any]) -> list[Any]:
        """Send ``cmd`` to the workers holding ``indices``; answers in the order of ``indices``."""
        wanted = list(self._get_indices(indices))
        by_worker: dict[int, list[int]] = {}
        for i in wanted:
            w = next(k for k, (start, stop) in enumerate(self.blocks) if start <= i < stop)
            by_worker.setdefault(w, []).append(i)
        asked = [w for w in by_worker if w > 0]
        for w in asked:
            self.workers.send(w - 1, cmd, make_data([i - self.blocks[w][0] for i in by_worker[w]]))
        local = (lambda: _answer(self.local, cmd, make_data(by_worker[0]))) if 0 in by_worker else None
        replies = self.workers.receive([w - 1 for w in asked], local)
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
