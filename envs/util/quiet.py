"""Silence text that C extensions write straight to the process's stdout and stderr."""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from collections.abc import Iterator

_LIBC = ctypes.CDLL(None)


@contextlib.contextmanager
def quiet_c_output() -> Iterator[None]:
    """Send C-level writes to stdout and stderr (fds 1 and 2) to /dev/null for the duration of the block.

    pybullet 3.2.7 prints its build banner to stderr and its URDF/shape warnings to stdout. libc buffers a
    stream that is not a terminal, so the C buffers are flushed before the descriptors are restored; otherwise
    the silenced text would surface later, at exit.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:  # no usable fds (some embedded interpreters): nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            os.dup2(devnull.fileno(), 2)
            yield
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        _LIBC.fflush(None)
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)
