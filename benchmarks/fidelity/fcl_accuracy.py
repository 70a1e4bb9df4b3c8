"""Accuracy of FCL's clearance on the query ClutterNav makes, against the closed form, by distance.

The chassis cylinder against floor-standing boxes, wall segments and cylinders taller than the robot: the exact
3D distance is the 2D distance between the footprints. Both of python-fcl's GJK solvers are run on the same
random positions, through the env's own query (``signed_distance``: FCL's raw signed query aborts the process on
some touching poses, so overlaps ask ``fcl.collide`` first).

    python -m benchmarks.fidelity.fcl_accuracy
"""

from __future__ import annotations

import argparse
import time

import fcl
import numpy as np

from benchmarks.harness import table_header
from clutter_gym.collision import obstacle_object
from clutter_gym.collision.distance import signed_distance
from clutter_gym.datatypes import Obstacle

CHASSIS_RADIUS = 0.17
OBSTACLES = (
    Obstacle("box", (0.6, 0.3, 0.5), (1.2, 0.4), 0.7),
    Obstacle("cylinder", (0.5, 0.5, 0.5), (-1.0, -1.3)),
    Obstacle("box", (1.8, 0.1, 0.5), (0.0, 2.0), -0.3),
)
BINS = ((0.0, 0.1), (0.1, 0.5), (0.5, 1.0), (1.0, 5.0))


def clearances(shape: fcl.CollisionGeometry, poses: list[tuple[np.ndarray, np.ndarray]],
               objects: list[fcl.CollisionObject], solver: fcl.GJKSolverType) -> np.ndarray:
    """(len(poses), len(objects)) signed distances, metres, from ``shape`` at each (rotation, position) to each
    object, asked as the env asks (:func:`signed_distance`) with ``solver``."""
    out = np.empty((len(poses), len(objects)))
    for i, (rotation, position) in enumerate(poses):
        robot = fcl.CollisionObject(shape, fcl.Transform(rotation, position))
        for k, o in enumerate(objects):
            out[i, k] = signed_distance(robot, o, solver=solver)[0]
    return out


def main(samples: int = 5000) -> None:
    rng = np.random.default_rng(0)
    points = rng.uniform(-2.7, 2.7, size=(samples, 2))
    exact = np.array([[float(o.distance(np.array(x), np.array(y))) - CHASSIS_RADIUS for o in OBSTACLES]
                      for x, y in points])
    objects = [obstacle_object(o) for o in OBSTACLES]
    chassis = fcl.Cylinder(CHASSIS_RADIUS, 0.12)
    print(f"{samples} random chassis positions x {len(OBSTACLES)} obstacles; error = |FCL - closed form|\n")
    print(table_header("GJK solver", *(f"max error, d in [{lo}, {hi}) m" for lo, hi in BINS), "us per pair"))
    for name, solver in (("libccd (default)", fcl.GJKSolverType.GST_LIBCCD),
                         ("FCL's own (GST_INDEP)", fcl.GJKSolverType.GST_INDEP)):
        poses = [(np.eye(3), np.array([x, y, 0.075])) for x, y in points]
        t0 = time.perf_counter()
        got = clearances(chassis, poses, objects, solver)
        per_pair = (time.perf_counter() - t0) / got.size * 1e6
        valid = exact > 0  # penetrating placements have no closed-form 2D answer here
        err = np.abs(got - exact)
        cells = []
        for lo, hi in BINS:
            sel = valid & (exact >= lo) & (exact < hi)
            cells.append(f"{err[sel].max():.1e} (n={sel.sum()})" if sel.any() else "-")
        print(f"| {name} | {' | '.join(cells)} | {per_pair:.1f} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # --help; no options
    main()
