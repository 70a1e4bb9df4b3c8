"""Worker processes that serve a block of envs over a pipe: the pieces the vector envs share.

A vector env over a few cores splits its envs into contiguous blocks, steps the first block in its own process and
each other block in a worker process, one message per worker per vector step: a message costs about as much as a
step, so one per env (Gymnasium's ``AsyncVectorEnv``, SB3's ``SubprocVecEnv``) spends the second core on pipes.
"""

from __future__ import annotations

import multiprocessing as mp
import traceback
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np


class WorkerError:
    """An exception raised in a worker, sent back to be raised again in the parent with the worker's traceback."""

    def __init__(self, error: BaseException) -> None:
        self.error, self.trace = error, traceback.format_exc()


def blocks(n: int, workers: int) -> list[tuple[int, int]]:
    """``workers`` contiguous (start, stop) blocks over ``n`` envs, sizes differing by at most 1.

    Raises:
        ValueError: ``workers`` is not in [1, n].
    """
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or not 1 <= workers <= n:
        raise ValueError(f"workers must be an integer in [1, {n}] (one env at least per worker), got {workers!r}")
    bounds = np.linspace(0, n, workers + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def context(start_method: str | None = None) -> Any:
    """The multiprocessing context workers start in: ``start_method``, or forkserver where there is one (a fork of a
    process that holds pybullet clients and threads is unsafe), else spawn."""
    if start_method is None:
        start_method = "forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn"
    return mp.get_context(start_method)


def serve(remote: Any, parent_remote: Any, make: Callable[[], Any], answer: Callable[[Any, str, Any], Any]) -> None:
    """A worker's loop: build its block with ``make()``, then send ``answer(block, cmd, data)`` for each message until
    ``close`` (or the parent goes away); the env's own errors go back as :class:`WorkerError`."""
    parent_remote.close()
    block = make()
    while True:
        try:
            cmd, data = remote.recv()
        except (EOFError, KeyboardInterrupt):
            break
        if cmd == "close":
            block.close()
            remote.close()
            break
        try:
            remote.send(answer(block, cmd, data))
        except Exception as error:  # a bad action, a missing attribute: the caller's to see
            remote.send(WorkerError(error))


def gather(remotes: Sequence[Any], local: Callable[[], Any] | None = None) -> list[Any]:
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


def stop_workers(remotes: Sequence[Any], processes: Sequence[Any]) -> None:
    """Tell every worker to close its block, wait for the processes to end and close the pipes."""
    for remote in remotes:
        remote.send(("close", None))
    for process in processes:
        process.join()
    for remote in remotes:
        remote.close()
