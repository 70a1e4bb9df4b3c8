"""Relative links in README.md and docs/*.md point at files that exist, and their #anchors at real headings."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


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
