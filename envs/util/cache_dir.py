"""Where clutter-gym keeps what it derives once and reuses: allowed-collision matrices, prepared robot URDFs.

The folder is ``$XDG_CACHE_HOME/clutter-gym/<what>``, or ``$HOME/.cache/clutter-gym/<what>``. As the XDG base
directory specification says, a relative ``XDG_CACHE_HOME`` is ignored; an empty or relative ``HOME`` names no home
(``Path.home()`` would make an empty one ``/``). When there is no home, or the cache cannot be written (a read-only
home, a file in the way), the process uses a private temporary folder instead, removed when it exits, and says so
once with a warning: everything still works, only nothing is kept for the next process.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
import warnings
from pathlib import Path

_fallback: Path | None = None


def user_cache_dir(what: str) -> Path:
    """The cache folder for ``what`` (see the module docstring): a folder that is writable, or can be made where
    it is named (its writers make it; looking for a file in it makes nothing)."""
    try:
        folder = _cache_base() / "clutter-gym" / what
    except (RuntimeError, KeyError) as error:  # and when HOME is unset and the password database has no entry
        return _fallback_dir(str(error)) / what
    existing = folder
    while not existing.exists():  # a name under a file does not exist either
        existing = existing.parent
    if not (existing.is_dir() and os.access(existing, os.W_OK | os.X_OK)):
        return _fallback_dir(f"{existing} is not a writable folder") / what
    return folder


def _cache_base() -> Path:
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return Path(xdg)
    home = os.environ["HOME"] if "HOME" in os.environ else str(Path.home())  # unset: the password database's
    if not os.path.isabs(home):
        raise RuntimeError(f"HOME is {home!r}, not an absolute path")
    return Path(home) / ".cache"


def _fallback_dir(reason: str) -> Path:
    """This process's temporary cache, made (and the warning given) on first use."""
    global _fallback
    if _fallback is None:
        _fallback = Path(tempfile.mkdtemp(prefix="clutter-gym-cache-"))  # private to this user: mode 0700
        atexit.register(shutil.rmtree, _fallback, ignore_errors=True)
        warnings.warn(f"clutter-gym cannot use its cache ({reason}); this process caches in {_fallback}, removed "
                      "when it exits", RuntimeWarning, stacklevel=3)
    return _fallback
