"""Speed against error of LIDAR rays on cylinder obstacles: Bullet's cylinder primitive vs n-gon trimesh prisms.

Twenty cylinders (r = 0.2 m) ring a 64-beam scan; the error is measured on 400 beams fanned across one cylinder
against the exact ray-circle intersection. Prisms have the circle's area (see clutter_gym.util.meshes.prism_mesh).

    python -m benchmarks.cylinder_rays
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from benchmarks.harness import pb, table_header
from clutter_gym.sim import CYLINDER_SIDES
from clutter_gym.util.meshes import prism_mesh
from clutter_gym.util.quiet import quiet_c_output

R, H = 0.2, 0.5


def collision_shape(cid: int, kind: str, sides: int) -> int:
    if kind == "primitive":
        return pb.createCollisionShape(pb.GEOM_CYLINDER, radius=R, height=H, physicsClientId=cid)
    vertices, indices = prism_mesh(R, H, sides)
    return pb.createCollisionShape(pb.GEOM_MESH, vertices=vertices, indices=indices,
                                   flags=pb.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=cid)


def scan_time_us(kind: str, sides: int) -> float:
    with quiet_c_output():
        cid = pb.connect(pb.DIRECT)
    shape = collision_shape(cid, kind, sides)
    for i in range(20):
        a = 2 * math.pi * i / 20
        pb.createMultiBody(0, shape, -1, [2 * math.cos(a), 2 * math.sin(a), H / 2], physicsClientId=cid)
    beams = -math.pi + 2 * math.pi * np.arange(64) / 64 + 0.013
    starts = [[0.05 * math.cos(b), 0.05 * math.sin(b), 0.2] for b in beams]
    ends = [[5 * math.cos(b), 5 * math.sin(b), 0.2] for b in beams]
    t0, n = time.perf_counter(), 300
    for _ in range(n):
        pb.rayTestBatch(starts, ends, numThreads=1, physicsClientId=cid)
    pb.disconnect(cid)
    return (time.perf_counter() - t0) / n * 1e6


def range_errors_mm(kind: str, sides: int) -> np.ndarray:
    with quiet_c_output():
        cid = pb.connect(pb.DIRECT)
    pb.createMultiBody(0, collision_shape(cid, kind, sides), -1, [2, 0, H / 2], physicsClientId=cid)
    beams = np.linspace(-0.099, 0.099, 400)  # 0.1 rad is the cylinder's half-angle seen from the origin
    hits = pb.rayTestBatch([[0, 0, 0.2]] * len(beams), [[5 * math.cos(b), 5 * math.sin(b), 0.2] for b in beams],
                           physicsClientId=cid)
    pb.disconnect(cid)
    b = 2 * np.cos(beams)
    exact = b - np.sqrt(b * b - (4 - R * R))
    return 1000 * (5 * np.array([h[2] for h in hits]) - exact)


MODELS = (("primitive", 0), ("prism", 16), ("prism", 32), ("prism", 64))


def rows() -> list[dict]:
    """Per cylinder model: label, scan time (us), max and mean range error (mm), and whether the envs use it."""
    out = []
    for kind, sides in MODELS:
        err = range_errors_mm(kind, sides)
        label = "Bullet cylinder primitive" if kind == "primitive" else f"{sides}-gon trimesh prism"
        out.append({"label": label, "scan_us": scan_time_us(kind, sides), "max_mm": float(np.abs(err).max()),
                    "mean_mm": float(err.mean()), "default": kind == "prism" and sides == CYLINDER_SIDES})
    return out


def main() -> None:
    print(table_header("cylinder model", "64-beam scan, 20 cylinders (us)", "max range error (mm)", "mean error (mm)"))
    for r in rows():
        label = f"{r['label']} (the envs')" if r["default"] else r["label"]
        print(f"| {label} | {r['scan_us']:.0f} | {r['max_mm']:.2f} | {r['mean_mm']:+.3f} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # --help; no options
    main()
