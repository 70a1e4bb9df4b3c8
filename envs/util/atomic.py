"""Files that appear complete or not at all: write beside the target, then rename over it.

Temporary files and folders are created with the modes a plain ``open``/``mkdir`` would give them (0666 and
0777 less the process umask), so what lands is as readable to other users as any file the user writes; the
``tempfile`` helpers would leave 0600 files and 0700 folders whatever the umask.
"""

from __future__ import annotations

import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def _fresh_name(target: Path, tag: str = "") -> Path:
    """A hidden name beside ``target`` that keeps its suffix (writers such as imageio pick the format from it)."""
    return target.parent / f".{target.name}.{tag}{secrets.token_hex(6)}{target.suffix}"


def _create(target: Path, make) -> Path:
    """Create a fresh temporary entry beside ``target`` with ``make(path)``, retrying on the rare name clash."""
    target.parent.mkdir(parents=True, exist_ok=True)
    while True:
        path = _fresh_name(target)
        try:
            make(path)
            return path
        except FileExistsError:
            continue


def _new_file(path: Path) -> None:
    os.close(os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))  # the umask applies, as for open()


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; on success rename it to ``path``, on error delete it.

    The temporary name keeps the target's suffix, so writers that pick a format from it (imageio, SB3's
    ``.zip``) behave as for the real name. ``os.replace`` is atomic on one file system: a reader sees the old
    file or the new one, never a half-written one, even if the process is killed mid-write.
    """
    path = Path(path)
    tmp = _create(path, _new_file)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomically(path: str | Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


@contextmanager
def atomic_folder(path: str | Path) -> Iterator[Path]:
    """Yield a fresh temporary folder beside ``path``; on success it takes the name ``path`` (replacing any old one).

    A folder rename is atomic, so a folder under the final name is always complete. When an old folder is being
    replaced it is first renamed aside, so for a moment neither name may exist, but a complete copy always does.
    """
    path = Path(path)
    tmp = _create(path, os.mkdir)  # mode 0777 less the umask
    try:
        yield tmp
        if path.exists():
            old = _create(path, os.mkdir)
            os.replace(path, old / path.name)
            os.replace(tmp, path)
            shutil.rmtree(old)
        else:
            os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
