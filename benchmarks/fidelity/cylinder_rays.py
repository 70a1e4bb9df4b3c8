"""Speed against error of LIDAR rays on cylinder obstacles: the exact caster (the LIDAR's default), and pybullet's
rays on Bullet's cylinder primitive and on n-gon trimesh prisms (the collision shape of the envs' cylinders).

Twenty cylinders (r = 0.2 m) ring a 64-beam scan; the error is measured on 400 beams fanned across one cylinder
against the exact ray-circle intersection. Prisms have the circle's area (see clutter_gym.util.meshes.prism_mesh).
The exact caster casts against the same Sim's true cylinders (``Sim.ray_hit_fractions(caster="exact")``).

    python -m benchmarks.fidelity.cylinder_rays
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from benchmarks.harness import pb, table_header
from clutter_gym.sim import CYLINDER_SIDES, Sim
from clutter_gym.util.meshes import prism_mesh
from clutter_gym.util.quiet import quiet_c_output

R, H = 0.2, 0.5


def collision_shape(cid: int, kind: str, sides: int) -> int:
    if kind == "primitive":
        return pb.createCollisionShape(pb.GEOM_CYLINDER, radius=R, height=H, physicsClientId=cid)
    vertices, indices = prism_mesh(R, H, sides)
    return pb.createCollisionShape(pb.GEOM_MESH, vertices=vertices, indices=indices,
                                   flags=pb.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=cid)


def _scan() -> tuple[list, list]:
    beams = -math.pi + 2 * math.pi * np.arange(64) / 64 + 0.013
    starts = [[0.05 * math.cos(b), 0.05 * math.sin(b), 0.2] for b in beams]
    ends = [[5 * math.cos(b), 5 * math.sin(b), 0.2] for b in beams]
    return starts, ends


def _fan() -> tuple[np.ndarray, list, list]:
    """400 beams fanned across a cylinder 2 m ahead (0.1 rad is its half-angle seen from the origin)."""
    beams = np.linspace(-0.099, 0.099, 400)
    return beams, [[0, 0, 0.2]] * len(beams), [[5 * math.cos(b), 5 * math.sin(b), 0.2] for b in beams]


def _exact_mm(beams: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    b = 2 * np.cos(beams)
    return 1000 * (5 * fractions - (b - np.sqrt(b * b - (4 - R * R))))


def exact_caster() -> tuple[float, np.ndarray]:
    """The exact caster's scan time (us) among the 20 cylinders and its range errors (mm) on the fan."""
    sim = Sim(visuals=False)
    try:
        sim.obstacles.add_static_cylinders(R, H, (1, 1, 1, 1), [[2 * math.cos(a), 2 * math.sin(a), H / 2]
                                                      for a in 2 * math.pi * np.arange(20) / 20])
        starts, ends = (np.array(v) for v in _scan())
        sim.rays.ray_hit_fractions(starts, ends, caster="exact")  # compiled (or loaded from numba's cache) untimed
        t0, n = time.perf_counter(), 300
        for _ in range(n):
            sim.rays.ray_hit_fractions(starts, ends, caster="exact")
        seconds = (time.perf_counter() - t0) / n
    finally:
        sim.close()
    sim = Sim(visuals=False)
    try:
        sim.obstacles.add_static_cylinders(R, H, (1, 1, 1, 1), [[2, 0, H / 2]])
        beams, starts, ends = _fan()
        errors = _exact_mm(beams, sim.rays.ray_hit_fractions(np.array(starts), np.array(ends), caster="exact"))
    finally:
        sim.close()
    return seconds * 1e6, errors


def scan_time_us(kind: str, sides: int) -> float:
    """pybullet's scan time (us) among the 20 cylinders of one model."""
    with quiet_c_output():
        cid = pb.connect(pb.DIRECT)
    shape = collision_shape(cid, kind, sides)
    for i in range(20):
        a = 2 * math.pi * i / 20
        pb.createMultiBody(0, shape, -1, [2 * math.cos(a), 2 * math.sin(a), H / 2], physicsClientId=cid)
    starts, ends = _scan()
    t0, n = time.perf_counter(), 300
    for _ in range(n):
        pb.rayTestBatch(starts, ends, numThreads=1, physicsClientId=cid)
    pb.disconnect(cid)
    return (time.perf_counter() - t0) / n * 1e6


def range_errors_mm(kind: str, sides: int) -> np.ndarray:
    """pybullet's range errors (mm) on the fan, one model."""
    with quiet_c_output():
        cid = pb.connect(pb.DIRECT)
    pb.createMultiBody(0, collision_shape(cid, kind, sides), -1, [2, 0, H / 2], physicsClientId=cid)
    beams, starts, ends = _fan()
    hits = pb.rayTestBatch(starts, ends, physicsClientId=cid)
    pb.disconnect(cid)
    return _exact_mm(beams, np.array([h[2] for h in hits]))


MODELS = (("primitive", 0), ("prism", 16), ("prism", 32), ("prism", 64))


def rows() -> list[dict]:
    """Per caster and cylinder model: label, scan time (us), max and mean range error (mm), and whether the LIDAR
    uses it by default."""
    seconds, err = exact_caster()
    out = [{"label": "exact caster (true cylinders)", "scan_us": seconds, "max_mm": float(np.abs(err).max()),
            "mean_mm": float(err.mean()), "default": True}]
    for kind, sides in MODELS:
        err = range_errors_mm(kind, sides)
        label = "pybullet, Bullet cylinder primitive" if kind == "primitive" else f"pybullet, {sides}-gon prism"
        if sides == CYLINDER_SIDES:
            label += " (the envs' collision shape)"
        out.append({"label": label, "scan_us": scan_time_us(kind, sides), "max_mm": float(np.abs(err).max()),
                    "mean_mm": float(err.mean()), "default": False})
    return out


def main() -> None:
    print(table_header("caster, cylinder model", "64-beam scan, 20 cylinders (us)", "max range error (mm)",
                       "mean error (mm)"))
    for r in rows():
        label = f"**{r['label']}** (default)" if r["default"] else r["label"]
        print(f"| {label} | {r['scan_us']:.0f} | {r['max_mm']:.2g} | {r['mean_mm']:+.3f} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # --help; no options
    main()
