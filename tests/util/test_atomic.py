"""Files and folders written atomically survive a writer that dies half way; videos come out in both formats."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest

from clutter_gym.util.atomic import atomic_folder, atomic_path, write_text_atomically
from clutter_gym.util.video import write_video


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "summary.json"
    write_text_atomically(target, "old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half of the new")
        raise RuntimeError("killed")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]


def test_a_folder_replaced_atomically_is_whole_before_and_after(tmp_path):
    target = tmp_path / "model"
    with atomic_folder(target) as tmp:
        (tmp / "a").write_text("1")
    with pytest.raises(RuntimeError), atomic_folder(target) as tmp:
        (tmp / "a").write_text("2")
        raise RuntimeError("killed")
    assert (target / "a").read_text() == "1"
    with atomic_folder(target) as tmp:
        (tmp / "a").write_text("3")
    assert (target / "a").read_text() == "3"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model"]


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_videos_are_written_in_the_format_of_their_suffix(tmp_path, suffix):
    pytest.importorskip("imageio_ffmpeg") if suffix == ".mp4" else None
    frames = [np.full((50, 70, 3), 20 * i, dtype=np.uint8) for i in range(6)]
    path = write_video(tmp_path / f"episode{suffix}", frames, fps=10)
    head = path.read_bytes()[:12]
    assert head.startswith(b"GIF8") if suffix == ".gif" else head[4:8] == b"ftyp"


def test_bad_video_requests_are_refused(tmp_path):
    with pytest.raises(ValueError, match=".gif or .mp4|one of"):
        write_video(tmp_path / "episode.avi", [np.zeros((4, 4, 3), np.uint8)], fps=10)
    with pytest.raises(ValueError, match="no frames"):
        write_video(tmp_path / "episode.gif", [], fps=10)


@pytest.fixture(params=[0o022, 0o077, 0o002])
def umask(request):
    old = os.umask(request.param)
    yield request.param
    os.umask(old)


def test_written_files_and_folders_honour_the_umask(tmp_path, umask):
    write_text_atomically(tmp_path / "a.json", "{}")
    with atomic_path(tmp_path / "frame.png") as tmp:
        tmp.write_bytes(b"\x89PNG")
    with atomic_folder(tmp_path / "nested" / "model") as folder:
        (folder / "model.zip").write_bytes(b"PK")
    with atomic_folder(tmp_path / "nested" / "model") as folder:  # the replacing path too
        (folder / "model.zip").write_bytes(b"PK")
    modes = {p.relative_to(tmp_path).as_posix(): stat.S_IMODE(p.stat().st_mode) for p in tmp_path.rglob("*")}
    assert modes == {
        "a.json": 0o666 & ~umask,
        "frame.png": 0o666 & ~umask,
        "nested": 0o777 & ~umask,
        "nested/model": 0o777 & ~umask,
        "nested/model/model.zip": 0o666 & ~umask,
    }
