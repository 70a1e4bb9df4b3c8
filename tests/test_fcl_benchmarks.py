"""The FCL benchmarks ask for signed distances through the env's guarded query, so they measure what the env
measures and survive the poses where FCL's raw signed query aborts the process.

FCL 0.7's EPA throws a C++ ``std::logic_error`` that python-fcl does not translate when two faces touch with a tiny
tilt, which ends the whole process; ``clutter_gym.collision.distance.signed_distance`` asks ``fcl.collide`` first
(tests/hard_cases/test_degenerate_meshes.py). ``benchmarks.fidelity.fcl_accuracy`` asks it with each of FCL's GJK
solvers, and the brute force of ``benchmarks.fidelity.collision_fidelity`` for a robot model's shapes with their
solids; no benchmark asks FCL's raw signed query itself. The poses below are two of the 800 seeded touching poses of
that test that abort the raw query (``enable_signed_distance``); the guarded query is asked both ways on them in a
child process, so an abort fails this test instead of ending the run.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: (rotation vector, position) of a 0.2 m box whose +x face touches a 0.4 m box's -x face (the plane x = 0.3)
POSES = """[
    ([1.2954518814024666e-12, -6.306262185848895e-13, 3.3324299657329023e-13], [0.20000000023077025, 0.0, 0.2]),
    ([3.341451131848685e-08, 3.1458749614884534e-09, -1.0566295174251145e-08], [0.19999999982931171, 0.0, 0.2]),
]"""
SETUP = f"""
import fcl
import numpy as np
from scipy.spatial.transform import Rotation
poses = [(Rotation.from_rotvec(r).as_matrix(), np.array(p)) for r, p in {POSES}]
obstacle = fcl.CollisionObject(fcl.Box(0.4, 0.4, 0.4), fcl.Transform(np.eye(3), np.array([0.5, 0.0, 0.2])))
reach = 0.1 * np.sqrt(3) * 3.6e-8 + 1e-9  # the tilted box's corners reach this far past the touching face, at most
"""


def run_child(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(SETUP) + textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=300, cwd=ROOT)


@pytest.mark.parametrize("solver", ["GST_LIBCCD", "GST_INDEP"])
def test_each_gjk_solver_measures_touching_tilted_boxes_without_aborting(solver):
    """As ``fcl_accuracy`` asks: a shape at each pose against an obstacle, with the solver it compares."""
    result = run_child(f"""
        from clutter_gym.collision.distance import signed_distance
        for rotation, position in poses:
            box = fcl.CollisionObject(fcl.Box(0.2, 0.2, 0.2), fcl.Transform(rotation, position))
            d = signed_distance(box, obstacle, solver=fcl.GJKSolverType.{solver})[0]
            assert abs(d) <= reach, d
        print("checked")
    """)
    assert result.returncode == 0 and "checked" in result.stdout, (result.returncode, result.stderr[-2000:])


def test_a_robot_models_shape_measures_touching_tilted_boxes_without_aborting(tmp_path):
    """As ``collision_fidelity``'s brute force asks: a robot model's shape, its solid answering in overlap."""
    urdf = tmp_path / "box.urdf"
    urdf.write_text('<robot name="box"><link name="part"><collision><geometry><box size="0.2 0.2 0.2"/></geometry>'
                    '</collision></link></robot>\n')
    result = run_child(f"""
        from clutter_gym.collision import RobotCollisionModel
        from clutter_gym.collision.distance import signed_distance
        model = RobotCollisionModel.from_urdf({str(urdf)!r}, "primitive", ("part",), self_collision=False)
        for rotation, position in poses:
            model.sync(position[None], rotation[None])
            d = signed_distance(model.objects[0], obstacle, model.solid_objects[0])[0]
            assert abs(d) <= reach, d
        print("checked")
    """)
    assert result.returncode == 0 and "checked" in result.stdout, (result.returncode, result.stderr[-2000:])


def test_no_benchmark_asks_fcls_raw_signed_query():
    raw = [path.relative_to(ROOT).as_posix() for path in sorted((ROOT / "benchmarks").rglob("*.py"))
           if "enable_signed_distance" in path.read_text(encoding="utf-8")]
    assert not raw, f"ask clutter_gym.collision.distance.signed_distance instead: {raw}"
