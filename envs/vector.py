""":class:`BlockVectorEnv`: the envs' ``vector_entry_point``, N envs over the cores in blocks, one message per worker.

``gym.make_vec("ClutterNav-v1", num_envs=16)`` (or ``vectorization_mode="vector_entry_point"``) makes one. Its envs
are split into contiguous blocks, one per worker; the first block steps in this process while each other block
steps in a worker process of its own (:mod:`clutter_gym.util.workers`). Each block is a Gymnasium
``SyncVectorEnv``, so env ``i`` is the env ``gym.make`` gives, seeded ``seed + i``, with Gymnasium's next-step
autoreset, whatever the number of workers: the split changes the speed, never a trajectory, an observation or an
``info``.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, SyncVectorEnv, VectorEnv
from gymnasium.vector.utils import CloudpickleWrapper

from clutter_gym.util.workers import DEFAULT_TIMEOUT, Workers, blocks, check_actions, serve


def _block(env_id: str, count: int, kwargs: dict[str, Any]) -> SyncVectorEnv:
    return SyncVectorEnv([functools.partial(gym.make, env_id, **kwargs)] * count,
                         autoreset_mode=AutoresetMode.NEXT_STEP)


def _answer(block: SyncVectorEnv, cmd: str, data: Any) -> Any:
    if cmd == "step":
        return block.step(data)
    if cmd == "reset":
        seed, options = data
        return block.reset(seed=seed, options=options)
    if cmd == "call":
        name, args, kwargs = data
        return block.call(name, *args, **kwargs)
    if cmd == "get_attr":
        return block.get_attr(data)
    if cmd == "set_attr":
        return block.set_attr(*data)
    if cmd == "render":
        return block.render()
    raise NotImplementedError(f"worker command {cmd!r}")


def _serve(remote: Any, parent_remote: Any, env_id: str, count: int, kwargs: CloudpickleWrapper) -> None:
    serve(remote, parent_remote, functools.partial(_block, env_id, count, kwargs.fn), _answer)


def _concat(parts: Sequence[Any]) -> Any:
    """Batched observations of several blocks as one batch (dicts key by key)."""
    if len(parts) == 1:
        return parts[0]
    if isinstance(parts[0], dict):
        return {key: _concat([p[key] for p in parts]) for key in parts[0]}
    return np.concatenate(parts)


def _merge_infos(parts: Sequence[dict[str, Any]], spans: Sequence[tuple[int, int]], n: int) -> dict[str, Any]:
    """The blocks' ``info`` dicts (Gymnasium's layout: an array per key, a boolean ``_key`` mask) as the one dict a
    ``SyncVectorEnv`` over all ``n`` envs gives: each key's array is typed by the first env that has it, as
    Gymnasium's ``_add_info`` types it, and holds every other env's value where that env's mask says it has one."""
    if len(parts) == 1:
        return parts[0]
    merged: dict[str, Any] = {}
    keys = dict.fromkeys(k for part in parts for k in part)
    for key in keys:
        if key.startswith("_") and key[1:] in keys:
            continue  # a mask: written with its key
        mask = f"_{key}"
        values = [part.get(key) for part in parts]
        first = next(v for v in values if v is not None)
        if isinstance(first, dict):
            merged[key] = _merge_infos([{} if v is None else v for v in values], spans, n)
        elif all(v is not None and v.dtype == first.dtype and v.shape[1:] == first.shape[1:] for v in values):
            merged[key] = np.concatenate(values)  # alike in every block: the rows without a value hold the same fill
        else:
            merged[key] = _typed_by_first(key, parts, spans, n, first)
        merged[mask] = np.concatenate([part[mask] if mask in part else np.zeros(stop - start, dtype=np.bool_)
                                       for part, (start, stop) in zip(parts, spans)])
    return merged


def _typed_by_first(key: str, parts: Sequence[dict[str, Any]], spans: Sequence[tuple[int, int]], n: int,
                    first: np.ndarray) -> np.ndarray:
    """``key``'s array over all envs typed by ``first`` (the first block's), each block's values assigned env by env
    where its mask is set, as Gymnasium assigns them."""
    out = np.full(n, None, dtype=object) if first.dtype == object else np.zeros((n, *first.shape[1:]), first.dtype)
    for part, (start, _) in zip(parts, spans):
        if key in part:
            for j in np.flatnonzero(part[f"_{key}"]):
                out[start + j] = part[key][j]
    return out


class BlockVectorEnv(VectorEnv):
    """``num_envs`` copies of ``env_id`` over ``workers`` workers (default: one per core, at most one per env).

    Args:
        env_id: a registered env id.
        num_envs: number of envs, at least 1.
        workers: processes stepping them, this one included (1: all in this process).
        start_method: multiprocessing start method of the worker processes (default: forkserver where there is
            one, else spawn, as for the training's vector env: a fork of a process holding pybullet clients and
            threads is unsafe). Both start the worker from a fresh interpreter that imports the calling script, so
            a script that makes this env needs the ``if __name__ == "__main__":`` guard.
        worker_timeout: seconds a worker may take over one answer (its first also waits for it to build its envs)
            before it counts as stuck (default :data:`~clutter_gym.util.workers.DEFAULT_TIMEOUT`, far beyond any
            reset; None: no limit).
        **kwargs: the env's keyword arguments (``max_episode_steps`` included), as ``gym.make`` takes them.

    A worker that dies or stops answering raises :class:`~clutter_gym.util.workers.WorkerLostError` naming it, its
    envs and how it ended; every later call raises the same, and ``close`` ends and reaps the workers whatever
    their state.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, env_id: str, num_envs: int, workers: int | None = None, start_method: str | None = None,
                 worker_timeout: float | None = DEFAULT_TIMEOUT, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer of at least 1, got {num_envs!r}")
        workers = min(os.cpu_count() or 1, int(num_envs)) if workers is None else workers
        self.blocks = blocks(int(num_envs), workers)
        self.sizes = [stop - start for start, stop in self.blocks]
        # started first: they build their envs while this process builds its own; the kwargs cloudpickled, as a
        # fork would have passed them whatever they hold
        self.workers = Workers(_serve, [(env_id, size, CloudpickleWrapper(kwargs)) for size in self.sizes[1:]],
                               self.blocks[1:], start_method, worker_timeout)
        try:
            self.local = _block(env_id, self.sizes[0], kwargs)
        except BaseException:  # a bad env argument: the workers meet it too; none is left behind
            self.workers.close(grace=0.0)
            raise
        self.num_envs = int(num_envs)
        self.single_observation_space = self.local.single_observation_space
        self.single_action_space = self.local.single_action_space
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, self.num_envs)
        self.metadata = {**self.local.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self.render_mode = self.local.render_mode
        self.closed = False

    @property
    def processes(self) -> list[Any]:
        """The worker processes (``multiprocessing.Process``), one per block after the first."""
        return self.workers.processes

    def _call_blocks(self, cmd: str, data: Sequence[Any]) -> list[Any]:
        """Send worker ``k`` (``k`` >= 1) ``(cmd, data[k])`` and answer ``data[0]`` here meanwhile; answers in block
        order."""
        if self.closed:
            raise RuntimeError("this vector env is closed")
        for k, item in enumerate(data[1:]):
            self.workers.send(k, cmd, item)
        return self.workers.receive(range(len(data) - 1), lambda: _answer(self.local, cmd, data[0]))

    def reset(self, *, seed: int | Sequence[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        if options and "reset_mask" in options:
            raise ValueError("options['reset_mask'] is for Gymnasium's same-step and disabled autoreset modes; this "
                             "vector env resets an ended env itself, on the next step")
        if seed is None or isinstance(seed, (int, np.integer)):
            seeds = [None if seed is None else int(seed) + start for start, _ in self.blocks]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed must be an int or a list of {self.num_envs} seeds, got {len(seeds)}")
            seeds = [seeds[start:stop] for start, stop in self.blocks]
        results = self._call_blocks("reset", [(s, options) for s in seeds])
        obs, infos = zip(*results)
        return _concat(obs), _merge_infos(infos, self.blocks, self.num_envs)

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        actions = check_actions(actions, self.action_space.shape)
        results = self._call_blocks("step", [actions[start:stop] for start, stop in self.blocks])
        obs, rewards, terminations, truncations, infos = zip(*results)
        return (_concat(obs), np.concatenate(rewards), np.concatenate(terminations), np.concatenate(truncations),
                _merge_infos(infos, self.blocks, self.num_envs))

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """``getattr(env, name)(*args, **kwargs)`` (or the attribute) of every env, in env order."""
        return tuple(v for part in self._call_blocks("call", [(name, args, kwargs)] * len(self.blocks)) for v in part)

    def get_attr(self, name: str) -> tuple[Any, ...]:
        return tuple(v for part in self._call_blocks("get_attr", [name] * len(self.blocks)) for v in part)

    def set_attr(self, name: str, values: Any) -> None:
        """Set attribute ``name`` of every env: to ``values[i]`` for env ``i`` given a list or tuple of
        ``num_envs`` values, else to ``values``."""
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(f"values must be one value or a list of {self.num_envs}, got {len(values)}")
        self._call_blocks("set_attr", [(name, list(values[start:stop])) for start, stop in self.blocks])

    def render(self) -> tuple[Any, ...] | None:
        parts = self._call_blocks("render", [None] * len(self.blocks))
        return None if parts[0] is None else tuple(frame for part in parts for frame in part)

    def close_extras(self, **kwargs: Any) -> None:
        """Close the envs here and in the workers, and end the workers (those that died or hang too)."""
        if self.closed:
            return
        try:
            self.workers.close()
        finally:
            self.closed = True
            self.local.close()


def make_block_vector_env(env_id: str) -> Any:
    """The ``vector_entry_point`` of ``env_id``: a callable ``gym.make_vec`` gives ``num_envs`` and the kwargs."""
    return functools.partial(BlockVectorEnv, env_id)
