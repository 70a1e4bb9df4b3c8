"""YAML from someone else (a robot spec file, a run folder's config.yaml, a hyperparameter file, a sweep's spec, a
command-line value) read with PyYAML's safe loader and bounds that keep a small file small.

The safe loader builds only plain data, so nothing it reads can run code. What it does not bound is size: an alias
(``*a``) stands for the whole node its anchor (``&a``) names, so a few hundred bytes of aliases of aliases stand for
gigabytes once anything walks the data (a repr in an error message, a dump, a merge). This loader counts, while it
parses, how big the document is with every alias expanded, and refuses it past :data:`MAX_EXPANDED`; it refuses an
alias inside the node it names (a structure that contains itself), nesting deeper than :data:`MAX_DEPTH`, and files
over :data:`MAX_BYTES`. Each refusal is a ValueError of one line that names the file (or what was read).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

import yaml

#: bytes: the largest YAML file read (specs, configs and hyperparameter files are a few kilobytes; PyYAML's
#: pure-Python parser, which the counting needs, takes seconds per hundred kilobytes of dense lists)
MAX_BYTES = 256 << 10
#: the document with every alias expanded, counted as its nodes plus the characters of its scalars: four times what
#: a file of MAX_BYTES without aliases can reach
MAX_EXPANDED = 4 * MAX_BYTES
#: the deepest nesting of sequences and mappings
MAX_DEPTH = 64


class _BoundedLoader(yaml.SafeLoader):
    """The safe loader, counting each parser event as the composer takes it (see the module docstring)."""

    def __init__(self, text: str) -> None:
        super().__init__(text)
        self._expanded = 0
        self._open: list[list[Any]] = []  # per open collection: [its anchor, its expanded size so far]
        self._sizes: dict[str, int] = {}  # expanded size of each finished anchored node

    def get_event(self) -> Any:
        event = super().get_event()
        if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
            if len(self._open) >= MAX_DEPTH:
                raise _Refused(f"nests deeper than {MAX_DEPTH} levels (line {event.start_mark.line + 1})")
            self._count(1)
            self._open.append([event.anchor, 1])
        elif isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
            anchor, size = self._open.pop()
            self._finish(anchor, size)
        elif isinstance(event, yaml.ScalarEvent):
            self._count(1 + len(event.value))
            self._finish(event.anchor, 1 + len(event.value))
        elif isinstance(event, yaml.AliasEvent):
            if any(anchor == event.anchor for anchor, _ in self._open):
                raise _Refused(f"alias *{event.anchor} inside the node &{event.anchor} names (line "
                               f"{event.start_mark.line + 1}): a structure that contains itself")
            size = self._sizes.get(event.anchor, 0)  # an undefined alias: the composer says so
            self._count(size)
            self._finish(None, size)
        return event

    def _count(self, size: int) -> None:
        """Count ``size`` more of the expanded document, and refuse it past the bound."""
        self._expanded += size
        if self._expanded > MAX_EXPANDED:
            raise _Refused(f"stands for more than {MAX_EXPANDED:,} nodes and characters with its aliases expanded "
                           "(aliases of aliases multiply)")

    def _finish(self, anchor: str | None, size: int) -> None:
        """A node of expanded ``size`` is complete: remember it under its anchor, and add it to its parent's size."""
        if anchor is not None:
            self._sizes[anchor] = size
        if self._open:
            self._open[-1][1] += size


class _Refused(Exception):
    """A bound the document broke; :func:`load_yaml` words it as a ValueError naming what was read."""


def load_yaml(text: str, where: str) -> Any:
    """The plain data (mappings, lists, strings, numbers, booleans, None) of the YAML ``text``.

    Raises:
        ValueError: ``text`` is longer than :data:`MAX_BYTES` characters, is not valid YAML, or breaks a bound of
            the module docstring; one line starting with ``where``.
    """
    if len(text) > MAX_BYTES:
        raise ValueError(f"{where} is longer than {MAX_BYTES:,} characters")
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_data()
    except _Refused as refused:
        raise ValueError(f"{where} {refused}") from None
    except yaml.YAMLError as error:
        raise ValueError(f"{where} is not valid YAML: {' '.join(str(error).split())}") from None
    except (ValueError, TypeError, OverflowError) as error:  # a scalar the constructor cannot make (a huge integer)
        raise ValueError(f"{where} holds a value YAML cannot read: {' '.join(str(error).split())}") from None
    finally:
        loader.dispose()


def read_yaml(path: str | Path, where: str | None = None) -> Any:
    """The plain data of the YAML file ``path`` (see :func:`load_yaml`); ``where`` names it in messages (default:
    the path).

    Raises:
        FileNotFoundError: no such file.
        ValueError: not a regular file, larger than :data:`MAX_BYTES`, not UTF-8 text, not valid YAML, or over a
            bound (one line starting with ``where``).
    """
    path = Path(path)
    where = where or str(path)
    with os.fdopen(os.open(path, os.O_RDONLY | os.O_NONBLOCK), "rb") as file:  # a FIFO opens without blocking ...
        info = os.fstat(file.fileno())  # ... and is refused here, with devices and folders
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"{where} is not a regular file")
        data = file.read(MAX_BYTES + 1)  # at most this much, whatever the size said (files under /proc say 0)
    if len(data) > MAX_BYTES:
        raise ValueError(f"{where} is larger than {MAX_BYTES:,} bytes")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{where} is not UTF-8 text (is it a YAML file?)") from None
    return load_yaml(text, where)
