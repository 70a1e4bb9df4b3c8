"""Each env's page in docs/envs/ is generated from its docstring and signature (benchmarks/env_pages.py): the
committed page is what the generator writes now, and the docstring names every constructor argument. So is
docs/sensors.md, from the sensor registry and the sensors' noise modules, and each registered sensor documents the
observation entries it adds."""

from __future__ import annotations

import re

import pytest

import clutter_gym
from benchmarks.env_pages import PAGES, SENSOR_PAGE, arguments, env_class, page, sensors_page
from clutter_gym.sensors import SENSORS


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


def test_the_committed_sensors_page_is_the_generated_one():
    assert SENSOR_PAGE.read_text(encoding="utf-8") == sensors_page(), (
        "docs/sensors.md differs from the sensor registry or the noise modules; run `python -m benchmarks.env_pages` "
        "and commit the page")


def test_each_registered_sensor_documents_the_entries_it_adds(make_env):
    env = make_env("ClutterNav-v1", sensors=tuple(SENSORS), camera_modes=("rgb", "depth", "segmentation")).unwrapped
    added = {sensor.name: set(sensor.spaces) for sensor in env.sensors}
    documented = {name: {row.key for row in entry.observation} for name, entry in SENSORS.items()}
    assert added == documented
    assert "| `odometry` | (6,) |" in sensors_page()
