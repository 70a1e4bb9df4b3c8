"""The layering docs/architecture.md states, checked on what each module loads in a fresh interpreter: URDF reading
and the robots' own models load no collision engine, the obstacle pool no simulator, and no robot model takes a
world's constants."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def loaded(module: str) -> set[str]:
    """The engines (fcl, pybullet, clutter_gym.sim) that importing ``module`` loads, in a fresh interpreter."""
    code = (f"import sys, {module}; print(' '.join(m for m in ('fcl', 'pybullet', 'clutter_gym.sim') "
            f"if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return set(out.split())


@pytest.mark.parametrize("module", ["clutter_gym.urdf.checks", "clutter_gym.urdf.geometry",
                                    "clutter_gym.urdf.kinematics", "clutter_gym.robots.arm_model",
                                    "clutter_gym.robots.wheel_checks"])
def test_reading_a_robot_s_urdf_loads_no_collision_engine(module):
    assert "fcl" not in loaded(module)


def test_the_obstacle_pool_loads_no_simulator():
    assert not loaded("clutter_gym.worlds.pool")


def test_no_robot_model_imports_a_world():
    importers = [path.name for path in sorted((ROOT / "envs" / "robots").glob("*.py"))
                 for node in ast.walk(ast.parse(path.read_text()))
                 if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("clutter_gym.worlds")]
    assert not importers, f"robot models that import a world: {importers}"
