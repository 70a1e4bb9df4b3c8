"""Worker processes that serve a block of envs over a pipe: the pieces the vector envs share.

A vector env over a few cores splits its envs into contiguous blocks, steps the first block in its own process and
each other block in a worker process, one message per worker per vector step: a message costs about as much as a
step, so one per env (Gymnasium's ``AsyncVectorEnv``, SB3's ``SubprocVecEnv``) spends the second core on pipes.

A worker can die (killed, out of memory) or stop answering (stopped, stuck). :class:`Workers` then raises a
:class:`WorkerLostError` that names the worker, its envs, its process and how it ended, instead of a bare
``BrokenPipeError`` or a wait without end; a vector env that lost a worker refuses every further call with that
message, and its ``close`` still ends and reaps every worker.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import signal
import time
import traceback
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

import numpy as np

#: Seconds a worker may take over one answer before it counts as lost, unless the vector env is given another
#: ``worker_timeout``: far beyond any reset or step the envs take (a worker's first answer also waits for it to
#: build its envs), so that only a stopped or stuck worker meets it.
DEFAULT_TIMEOUT = 1800.0
#: Seconds ``close`` waits for the workers to close their envs and exit before it kills them.
CLOSE_GRACE = 10.0


class WorkerError:
    """An exception raised in a worker, sent back to be raised again in the parent with the worker's traceback."""

    def __init__(self, error: BaseException) -> None:
        self.error, self.trace = error, traceback.format_exc()


class WorkerLostError(RuntimeError):
    """A worker process that died or gave no answer within the timeout: the vector env cannot go on."""


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


def check_timeout(timeout: Any) -> float | None:
    """A worker timeout: None (wait for ever) or a positive number of seconds; else a ``ValueError`` naming it."""
    if timeout is None:
        return None
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float, np.integer, np.floating)) \
            or not 0.0 < float(timeout) < math.inf:
        raise ValueError(f"worker_timeout must be a positive number of seconds or None (no limit), got {timeout!r}")
    return float(timeout)


def check_actions(actions: Any, shape: tuple[int, ...]) -> np.ndarray:
    """``actions`` as an array of ``shape`` (one row per env), checked before any worker is asked: a wrong number of
    rows would otherwise be cut short or padded by the blocks' slices. What is in the rows is each env's to check."""
    try:
        array = np.asarray(actions)
    except ValueError:  # ragged nesting
        array = None
    if array is None or array.shape != shape:
        got = "a ragged sequence" if array is None else f"shape {array.shape}"
        raise ValueError(f"actions must have shape {shape} (one row per env), got {got}")
    return array


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


class Workers:
    """The worker processes of a vector env, one per block of envs after the first (which the vector env steps
    itself): started in :func:`context`, asked over pipes, each answer awaited at most ``timeout`` seconds.

    Args:
        target: the worker's function, called as ``target(remote, parent_remote, *args)`` (it runs :func:`serve`).
        args: the further arguments of each worker, one tuple per worker process.
        spans: the (start, stop) envs of each worker process, for messages.
        start_method: see :func:`context`.
        timeout: seconds (or None: no limit) a worker may take over one answer.
    """

    def __init__(self, target: Callable[..., None], args: Sequence[tuple], spans: Sequence[tuple[int, int]],
                 start_method: str | None, timeout: float | None) -> None:
        self.timeout = check_timeout(timeout)
        self.spans = list(spans)
        self.remotes: list[Any] = []
        self.processes: list[Any] = []
        self.lost: str | None = None  # why the workers cannot go on, once one is lost
        self._lost_worker: int | None = None
        self._closed = False
        self._asked: dict[int, str] = {}  # worker -> the command it owes an answer to
        ctx = context(start_method)
        try:
            for extra in args:
                remote, work_remote = ctx.Pipe()
                process = ctx.Process(target=target, args=(work_remote, remote, *extra), daemon=True)
                process.start()  # daemon: never outlives a crashed parent
                work_remote.close()
                self.remotes.append(remote)
                self.processes.append(process)
        except BaseException:
            self.close(grace=0.0)
            raise

    def send(self, k: int, cmd: str, data: Any) -> None:
        """Send worker ``k`` (0: the first worker process) ``(cmd, data)``.

        Raises:
            WorkerLostError: a worker was lost, now or before.
        """
        self._check()
        try:
            self.remotes[k].send((cmd, data))
        except OSError:  # BrokenPipeError, ConnectionResetError: the worker is gone
            self._lose(k, f"died ({self._ending(k)}) before it took {cmd!r}")
        self._asked[k] = cmd

    def receive(self, which: Sequence[int], local: Callable[[], Any] | None = None) -> list[Any]:
        """``local()``'s answer (when given) and then one reply from each worker in ``which``, in that order, or the
        first error: every worker's reply is read first, so that none is left in a pipe, whatever raised.

        Raises:
            WorkerLostError: a worker died or gave no answer within the timeout.
        """
        try:
            answers = [] if local is None else [local()]
        finally:
            replies = [self._reply(k) for k in which]
        for reply in replies:
            if isinstance(reply, WorkerError):
                raise reply.error from RuntimeError(f"in an env worker process:\n{reply.trace}")
        return answers + replies

    def close(self, grace: float = CLOSE_GRACE) -> None:
        """Ask every worker to close its envs and exit; kill any that has not within ``grace`` seconds (a lost one at
        once), reap them all and close the pipes. Never raises for a worker that died or hangs; a second call does
        nothing."""
        if self._closed:
            return
        self._closed = True
        for k in self._asked:  # an answer still owed (a step sent, never awaited) could fill the pipe: read it
            if k != self._lost_worker and self.remotes[k].poll(grace):
                try:
                    self.remotes[k].recv()
                except (EOFError, OSError):
                    pass
        self._asked.clear()
        for remote in self.remotes:
            try:
                remote.send(("close", None))
            except OSError:  # already gone: reaped below
                pass
        deadline = time.monotonic() + grace
        for k, process in enumerate(self.processes):
            if k != self._lost_worker:
                process.join(max(0.0, deadline - time.monotonic()))
            if process.is_alive():
                process.kill()  # SIGKILL: ends a stopped process too
            process.join()
        for remote in self.remotes:
            remote.close()

    def _check(self) -> None:
        if self.lost is not None:
            raise WorkerLostError(self.lost)

    def _reply(self, k: int) -> Any:
        """Worker ``k``'s answer to what it was asked, awaited at most the timeout."""
        self._check()
        cmd = self._asked.pop(k)
        remote = self.remotes[k]
        try:
            if remote.poll(self.timeout):
                return remote.recv()
        except (EOFError, OSError):
            self._lose(k, f"died ({self._ending(k)}) while answering {cmd!r}")
        self._lose(k, f"gave no answer to {cmd!r} within {self.timeout:g} s (worker_timeout): it is stopped or stuck")

    def _lose(self, k: int, what: str) -> NoReturn:
        self._lost_worker = k
        start, stop = self.spans[k]
        self.lost = (f"env worker {k + 1} (envs {start}-{stop - 1}, process {self.processes[k].pid}) {what}; this "
                     "vector env cannot go on: close it and make a new one")
        raise WorkerLostError(self.lost)

    def _ending(self, k: int) -> str:
        """How worker ``k``'s process ended: its exit code, and the signal that killed it."""
        process = self.processes[k]
        process.join(1.0)
        code = process.exitcode
        if code is None:
            return "its pipe closed, the process still running"
        if code < 0:
            try:
                return f"exit code {code}, killed by {signal.Signals(-code).name}"
            except ValueError:
                return f"exit code {code}"
        return f"exit code {code}" + (": its error is printed above" if code else "")
