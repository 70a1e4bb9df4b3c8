"""YAML read from someone else's file stays small: each bound of the loader, seen through a robot spec file (the
alias bombs themselves: tests/robots/test_untrusted_specs.py and tests/training/test_run_folder_limits.py)."""

from __future__ import annotations

import gymnasium as gym
import pytest
from helpers import make_refusal, peak_mib

from clutter_gym.assets import asset_path

SPEC = (f"kind: diff_drive\nurdf: {asset_path('robots/diffbot.urdf')}\nleft_wheels: [left_wheel_joint]\n"
        "right_wheels: [right_wheel_joint]\n")


@pytest.mark.parametrize("text, message", [
    (SPEC + "mounts: &m {lidar_link: *m}\n", "alias *m inside the node &m names (line 5): a structure that contains "
                                             "itself"),
    (SPEC + "wheel_radius: " + "9" * 5000 + "\n", "holds a value YAML cannot read: Exceeds the limit (4300 digits)"),
    (SPEC + "# padding\n" * 30_000, "is larger than 262,144 bytes"),
])
def test_a_spec_file_past_a_bound_is_refused_in_one_line_naming_it(text, message, tmp_path, monkeypatch):
    """On main a structure that contained itself and a 300 KB file were read (the first reported as a bad mount),
    and a 5,000-digit number gave a raw ValueError that named no file."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    path = tmp_path / "bot.yaml"
    path.write_text(text)
    with pytest.raises(ValueError) as error:
        gym.make("ClutterNav-v1", robot=str(path))
    assert str(error.value).startswith(f"robot spec file {path} {message}") and "\n" not in str(error.value)


def test_a_spec_file_nested_too_deep_is_refused_before_the_parser_recurses(tmp_path):
    """On main 20,000 nested lists (40 KB) ran PyYAML's composer into a RecursionError; in a process of its own."""
    path = tmp_path / "bot.yaml"
    path.write_text(SPEC + "wheel_radius: " + "[" * 20_000 + "]" * 20_000 + "\n")
    result = make_refusal(str(path), tmp_path / "cache")
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout == f"robot spec file {path} nests deeper than 64 levels (line 5)\n"
    assert peak_mib(result) < 1024
