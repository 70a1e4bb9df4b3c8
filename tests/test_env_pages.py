"""Each env's page in docs/envs/ is generated from its docstring and signature (benchmarks/env_pages.py): the
committed page is what the generator writes now, and the docstring names every constructor argument."""

from __future__ import annotations

import re

import pytest

import clutter_gym
from benchmarks.env_pages import PAGES, arguments, env_class, page


@pytest.mark.parametrize("env_id", clutter_gym.ENV_IDS)
def test_the_committed_page_is_the_generated_one(env_id):
    committed = (PAGES / f"{env_id}.md").read_text(encoding="utf-8")
    assert committed == page(env_id), (f"docs/envs/{env_id}.md differs from its docstring; run "
                                       "`python -m benchmarks.env_pages` and commit the pages")


@pytest.mark.parametrize("env_id", clutter_gym.ENV_IDS)
def test_the_docstring_names_every_constructor_argument(env_id):
    doc = env_class(env_id).__doc__
    unnamed = [p.name for p in arguments(env_id)
               if not re.search(rf"``{re.escape(p.name)}``", doc)
               and not (p.name.endswith("_weight") and "``*_weight``" in doc)]
    assert not unnamed, f"{env_id}'s docstring does not name {unnamed}"


def test_the_page_turns_docstring_markup_into_markdown():
    text = page("ClutterNav-v1")
    assert "``" not in text and ":mod:" not in text and ":data:" not in text
    assert "[robots.md](../robots.md)" in text and "| `obstacle_density` | `0.12` |" in text
