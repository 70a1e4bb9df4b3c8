"""Where clutter-gym keeps what it derives once and reuses: allowed-collision matrices, prepared robot URDFs."""

from __future__ import annotations

import os
from pathlib import Path


def user_cache_dir(what: str) -> Path:
    """``$XDG_CACHE_HOME/clutter-gym/<what>`` (default ``~/.cache/clutter-gym/<what>``)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "clutter-gym" / what
