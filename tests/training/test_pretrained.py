"""The agents shipped inside the package: found by name, run by load, eval and demo, and still as good as their
cards say on the first held-out layouts of their evaluation."""

from __future__ import annotations

import pytest

from clutter_gym.cli import main
from clutter_gym.training import load
from clutter_gym.training.evaluate import evaluate
from clutter_gym.training.pretrained import card, pretrained_folder, pretrained_names

SHIPPED = ["ClutterFly-v1", "ClutterFly-v1-student", "ClutterNav-v1", "ClutterNav-v1-student", "ClutterReach-v1",
           "ClutterReach-v1-student"]


def test_the_shipped_agents_are_there_with_cards_that_say_how_they_were_made():
    assert pretrained_names() == SHIPPED
    for name in SHIPPED:
        info = card(name)
        assert info["command"].startswith("clutter-gym train --env ") and len(info["commit"]) >= 40
        assert info["evaluation"]["episodes"] == 100 and 0 <= info["check"]["min_success"] <= info["check"]["episodes"]


@pytest.mark.parametrize("name", SHIPPED)
def test_a_shipped_agent_still_reaches_its_documented_success(name):
    """The first layouts of the card's evaluation, rolled out again: a change to the env or to loading that costs
    the agent its success shows here (the threshold: ship_pretrained.min_success)."""
    info = card(name)
    summary = evaluate(f"pretrained/{name}", noise="none", episodes=info["check"]["episodes"],
                       seed=info["evaluation"]["seed"])
    successes = sum(bool(row["success"]) for row in summary["per_episode"])
    assert successes >= info["check"]["min_success"], (name, successes, info)


def test_a_student_acts_from_its_sensors_and_the_package_folder_is_left_as_it_was(tmp_path):
    folder = pretrained_folder("ClutterNav-v1-student")
    before = sorted((p.relative_to(folder), p.stat().st_mtime_ns) for p in folder.rglob("*"))
    agent = load("pretrained/ClutterNav-v1-student")
    env = agent.make_env()
    obs, _ = env.reset(seed=3)
    assert "subgoal" not in obs and set(obs) <= {"lidar", "goal", "velocity"}
    assert env.action_space.contains(agent.predict(obs)[0].astype(env.action_space.dtype))
    env.close()
    assert main(["eval", "pretrained/ClutterNav-v1-student", "--episodes", "1", "--no-progress"]) == 0
    assert sorted((p.relative_to(folder), p.stat().st_mtime_ns) for p in folder.rglob("*")) == before


def test_an_unknown_name_lists_the_shipped_ones():
    with pytest.raises(FileNotFoundError, match="no shipped agent is named 'nope'; the shipped agents: "
                                                "pretrained/ClutterFly-v1, "):
        load("pretrained/nope")


def test_the_demo_shows_a_shipped_agent(tmp_path, capsys):
    assert main(["demo", "--agent", "pretrained/ClutterNav-v1", "--max-steps", "20", "--out", str(tmp_path),
                 "--json"]) == 0
    out = capsys.readouterr().out
    assert '"policy": "trained agent pretrained/ClutterNav-v1"' in out and '"env": "ClutterNav-v1"' in out
    assert list(tmp_path.glob("ClutterNav-v1-seed0.gif"))
    with pytest.raises(SystemExit) as exit_info:
        main(["demo", "--agent", "pretrained/ClutterNav-v1", "--env", "ClutterFly-v1"])
    assert exit_info.value.code == 2
    assert "the agent pretrained/ClutterNav-v1 drives ClutterNav-v1" in capsys.readouterr().err
