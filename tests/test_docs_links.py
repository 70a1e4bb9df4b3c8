"""Relative links in README.md and docs/*.md point at files that exist, and their #anchors at real headings; the
benchmark commands they give name modules that exist."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "docs" / "envs").glob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
#: a command that runs a benchmark; placeholders in capitals (``python -m benchmarks.GROUP.NAME``) are not matched
BENCHMARK = re.compile(r"python3? -m (benchmarks(?:\.[a-z_][a-z0-9_]*)*)")


def _unfenced(page: Path) -> str:
    """The page without fenced code blocks, where brackets and '#' are not markdown."""
    return re.sub(r"^```.*?^```", "", page.read_text(encoding="utf-8"), flags=re.S | re.M)


def relative_links(page: Path) -> list[tuple[str, str]]:
    """(path, anchor) of each link that is neither external nor a pure in-page #anchor."""
    targets = LINK.findall(re.sub(r"`[^`\n]*`", "", _unfenced(page)))
    keep = [t for t in targets if not t.startswith(("http://", "https://", "mailto:", "#"))]
    return [tuple(t.partition("#")[::2]) for t in keep]


def slugs(page: Path) -> set[str]:
    """GitHub's heading anchors: lowercase, punctuation dropped (hyphens and spaces kept), spaces to hyphens."""
    headings = re.findall(r"^#{1,6}\s+(.*?)\s*#*\s*$", _unfenced(page), flags=re.M)
    return {re.sub(r"[^\w\- ]", "", h.lower()).replace(" ", "-") for h in headings}


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_point_at_existing_files(page):
    missing = [path for path, _ in relative_links(page) if not (page.parent / path).exists()]
    assert not missing, f"{page.relative_to(ROOT)} links to missing files: {missing}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_anchors_into_markdown_files_match_a_heading(page):
    bad = [f"{path}#{anchor}" for path, anchor in relative_links(page)
           if anchor and path.endswith(".md") and (page.parent / path).is_file()
           and anchor not in slugs(page.parent / path)]
    assert not bad, f"{page.relative_to(ROOT)} links to anchors with no heading: {bad}"


def exists(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is not None
    except ModuleNotFoundError:  # a package on the way is missing
        return False


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_benchmark_commands_name_modules_that_exist(page):
    """Finding a module imports only the packages above it (benchmarks/ and a group: docstrings); the benchmark
    itself is not imported."""
    commands = set(BENCHMARK.findall(page.read_text(encoding="utf-8")))
    missing = sorted(module for module in commands if not exists(module))
    assert not missing, f"{page.relative_to(ROOT)} gives python -m commands of modules that do not exist: {missing}"
