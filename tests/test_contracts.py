"""The contracts between the env core and its parts (interfaces.py, datatypes.py, the tasks): what they import, and
the orders of calls a part must not depend on. mypy holds each part to its protocol in ``python3 tasks.py test``."""

from __future__ import annotations

import ast
import pkgutil
import subprocess
import sys

import numpy as np
import pytest

from clutter_gym import tasks

ENGINES = ("pybullet", "fcl", "clutter_gym.sim", "clutter_gym.collision")
#: The tasks package and each of its modules: a task reads ground truth and never needs an engine.
TASK_MODULES = ["clutter_gym.tasks", *(f"clutter_gym.tasks.{m.name}" for m in pkgutil.iter_modules(tasks.__path__))]


def engines_loaded_by(*modules: str) -> list[str]:
    """The modules of :data:`ENGINES` that importing ``modules`` loads, in a fresh interpreter."""
    code = f"import sys, {', '.join(modules)}\nprint(sorted(m for m in {ENGINES!r} if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-2000:]
    return ast.literal_eval(result.stdout.strip())


def test_the_contracts_and_data_types_import_no_engine():
    assert engines_loaded_by("clutter_gym.interfaces", "clutter_gym.datatypes") == []


@pytest.mark.parametrize("module", TASK_MODULES)
def test_each_task_module_imports_no_engine(module):
    assert engines_loaded_by(module) == []


def test_the_reach_task_gives_the_same_step_whether_evaluate_or_observe_runs_first(make_env):
    """Both read the planned path's index, which moves forward with the joints once per state."""
    runs = []
    for evaluate_first in (False, True):
        env = make_env("ClutterReach-v1", subgoal_lookahead=0.2)
        env.reset(seed=3)
        core = env.unwrapped
        rng = np.random.default_rng(0)
        seen = []
        for _ in range(40):
            core.step(rng.uniform(-1.0, 1.0, 7))
            state = core.robot.state()
            report = core.checker.check(state, core.sim.contact_distances(core.robot.body))
            action = np.zeros(7)
            if evaluate_first:
                outcome = core.task.evaluate(state, report, action)
                obs = core.task.observe(state, report)
            else:
                obs = core.task.observe(state, report)
                outcome = core.task.evaluate(state, report, action)
            seen.append((obs["subgoal"].tolist(), outcome.reward, core.task.path.index))
        runs.append(seen)
    assert runs[0] == runs[1]
    assert runs[0][-1][2] > 0  # the path index moved: the comparison saw it move


def test_render_after_a_failed_reset_shows_the_robot_without_a_goal(make_env):
    env = make_env("ClutterNav-v1", render_mode="rgb_array")
    env.reset(seed=0)
    env.step(np.array([0.5, 0.0]))
    with pytest.raises(ValueError, match="scene"):
        env.reset(options={"scene": {"start": [0.0, 0.0]}})
    frame = env.render()
    assert frame.shape == (240, 320, 3)
