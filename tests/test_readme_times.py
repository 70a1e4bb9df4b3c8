"""Every time the README gives comes from the page that measured it, and the paragraph there that gives it says what
the machine was doing (issue 53.9: the README said 13-19 min for a job that took 4 min 22 s on an idle machine).

A figure's source is a ``docs/PAGE.md`` link or path (with or without ``#anchor``) in the same README paragraph,
list item or code line; the cited page (the anchor's section of it) must have a paragraph, list item or table row
that holds the figure and a word for the machine's state.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: a duration: 4.4 min, 13-19 min, 251 s, 2 hours (not a rate such as m/s or steps/s)
TIME = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?(?:-\d+(?:\.\d+)?)?) ?(min|minutes|s|h|hours)\b(?!/)")
SOURCE = re.compile(r"(docs/[\w.-]+\.md)(?:#([\w-]+))?")
STATE = re.compile(r"\bidle\b|\bshared\b|load average", re.I)


def blocks(text: str) -> list[str]:
    """Paragraphs and list items, and each line of the code blocks on its own."""
    found = []
    for part in re.split(r"(^```.*?^```)", text, flags=re.S | re.M):
        if part.startswith("```"):
            found += part.splitlines()[1:-1]
        else:
            found += re.split(r"\n\s*\n|\n(?=- |\| )", part)
    return found


def cited_text(path: str, anchor: str) -> str:
    """The page, or the section under the heading whose GitHub anchor is ``anchor`` down to the next heading of its
    level."""
    lines = (ROOT / path).read_text(encoding="utf-8").splitlines()
    if not anchor:
        return "\n".join(lines)
    for i, line in enumerate(lines):
        heading = re.match(r"^(#{1,6})\s+(.*?)\s*$", line)
        if heading and re.sub(r"[^\w\- ]", "", heading[2].lower()).replace(" ", "-") == anchor:
            end = next((j for j in range(i + 1, len(lines)) if re.match(rf"^#{{1,{len(heading[1])}}}\s", lines[j])),
                       len(lines))
            return "\n".join(lines[i:end])
    raise AssertionError(f"{path} has no heading #{anchor}")


def durations(text: str) -> list[tuple[str, str]]:
    return TIME.findall(re.sub(r"`[^`]*`", "", text))  # not what code says (`--timesteps 200000`, `0.3 s`)


TIMED = [block for block in blocks((ROOT / "README.md").read_text(encoding="utf-8")) if durations(block)]


def test_the_readme_gives_times():
    assert TIMED  # else the test below checks nothing


@pytest.mark.parametrize("block", TIMED, ids=lambda b: " ".join(b.split())[:60])
def test_each_time_in_the_readme_cites_its_measurement_and_the_machines_state(block):
    sources = SOURCE.findall(block)
    assert sources, f"no docs/PAGE.md cited for the time in: {block.strip()}"
    cited = [part for path, anchor in sources for part in blocks(cited_text(path, anchor))]
    for figure, unit in durations(block):
        giving = [part for part in cited if re.search(rf"(?<![\d.]){re.escape(figure)} ?{unit}\b", part)]
        assert giving, f"{figure} {unit} is nowhere in {sources}"
        assert any(STATE.search(part) for part in giving), \
            f"where {sources} give {figure} {unit}, they say not whether the machine was idle or shared"
