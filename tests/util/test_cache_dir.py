"""Where the cache is: the XDG base directory rules, and a private temporary folder, said once, when there is no
usable home."""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import pytest

from clutter_gym.util import cache_dir
from clutter_gym.util.cache_dir import user_cache_dir


@pytest.fixture(autouse=True)
def _fresh(monkeypatch):
    monkeypatch.setattr(cache_dir, "_fallback", None, raising=False)  # each test starts as a new process would


def test_a_relative_xdg_cache_home_is_ignored(tmp_path, monkeypatch):
    """The XDG specification: a relative path in these variables is invalid and ignored. On main it was used,
    relative to wherever the process ran."""
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")
    monkeypatch.setenv("HOME", str(tmp_path))
    assert user_cache_dir("robots") == tmp_path / ".cache" / "clutter-gym" / "robots"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert user_cache_dir("robots") == tmp_path / "xdg" / "clutter-gym" / "robots"


@pytest.mark.parametrize("home", ["", "relative/home"])
def test_no_usable_home_gives_a_private_temporary_folder_and_one_warning(home, monkeypatch):
    """On main ``HOME=""`` gave ``/.cache/clutter-gym/...`` (``Path.home()`` is ``/`` then), which root can write."""
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", home)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robots, acm = user_cache_dir("robots"), user_cache_dir("acm")
    assert [str(w.message).split(";")[0] for w in caught] == [
        f"clutter-gym cannot use its cache (HOME is {home!r}, not an absolute path)"]
    assert robots.parent == acm.parent and robots.parent.parent == Path(tempfile.gettempdir())
    assert robots.parent.stat().st_mode & 0o077 == 0  # private


def test_a_file_where_the_cache_should_be_gives_the_temporary_folder(tmp_path, monkeypatch):
    (tmp_path / "cache").write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    with pytest.warns(RuntimeWarning, match=f"{tmp_path / 'cache'} is not a writable folder"):
        folder = user_cache_dir("robots")
    assert not folder.is_relative_to(tmp_path)
