"""Collision fidelity levels: query cost against clearance error, FCL against pybullet, broad-phase scaling, env rate.

1. Fidelity table, per robot (Panda, diffbot): random configurations near obstacles (the ``mesh`` level's minimum
   clearance over the moving links in (0, 0.15] m; Panda: q uniform within the joint limits in seeded tabletop
   scenes plus the table; diffbot: random floor poses in seeded clutter scenes plus the arena walls). For each
   level: mean time of one environment query (``model.sync`` + ``checker.clearance``), of one self query
   (``model.self_clearance``), and the error of the minimum clearance against ``mesh`` on the same
   configurations (mean |err|, p95, max, share conservative = the level reports less clearance than mesh).
2. FCL against pybullet ``getClosestPoints`` (Panda, same scenes and configurations): a DIRECT client holds the
   Panda and the obstacles as static boxes and cylinders; one query is the minimum over every obstacle body
   (the fixed base, link -1, excluded), looped per body or restricted to the bodies pybullet's own broad phase
   (``getOverlappingObjects`` on the moving links' AABBs grown by the range) returns. Poses are set untimed on
   both sides (``resetJointState`` / numpy FK), as in an env step, where the link poses are already known.
3. Broad-phase scaling: N in 10..10000 small boxes (5-15 cm) scattered over a square whose side grows as
   sqrt(N) (fixed density, so about as many near the arm), Panda in random configurations: FCL's obstacle tree
   (``convex``), brute force (the checker's ``signed_distance`` on every moving-shape/obstacle pair) and pybullet
   (per-body loop and broad-phase variant). A method is extrapolated linearly in N where one query would take > 20 s.
4. Env throughput: ClutterReach-v1 at each level and panda-gym's PandaReach-v3, random actions, alternating
   blocks; medians over blocks.

Competitors run interleaved in one process (per scene, per configuration or per block), so machine noise hits
them alike; compare ratios rather than absolute times. Writes docs/collision_fidelity.md and .png.

    python -m benchmarks.fidelity.collision_fidelity            # about 5 min on 2 cores
    python -m benchmarks.fidelity.collision_fidelity --quick    # under a minute, fewer samples
"""

from __future__ import annotations

import argparse
import statistics
import time
from functools import partial
from pathlib import Path

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import alternating_rounds, pb, run_block, table_header
from clutter_gym.collision import (
    FIDELITY_LEVELS,
    CollisionChecker,
    RobotCollisionModel,
    UrdfKinematics,
    build_link_shapes,
    load_acm,
    load_collision_elements,
    obstacle_object,
)
from clutter_gym.collision.distance import signed_distance
from clutter_gym.datatypes import Obstacle
from clutter_gym.robots import DiffDriveRobot
from clutter_gym.robots.panda import REACH_RADIUS, READY, SHOULDER, PandaArm
from clutter_gym.training.figures import plt, save_figure
from clutter_gym.util.quiet import quiet_c_output
from clutter_gym.worlds.floor.arena import arena_walls
from clutter_gym.worlds.floor.sample import sample_scene
from clutter_gym.worlds.floor.spec import ClutterSpec
from clutter_gym.worlds.table.sample import sample_reach_scene
from clutter_gym.worlds.table.spec import TABLE, TableSpec

RANGE = 0.5  # clearance range, metres (the envs' default)
NEAR = 0.15  # configurations kept: mesh clearance in (0, NEAR]
FINGER_OPENING = 0.02  # the Panda's fingers, as in ClutterReach
DIFFBOT_Z = 0.05  # base_link height on the floor
SKIP_S = 20.0  # extrapolate a scaling method whose single query would take longer
DOCS = Path(__file__).resolve().parents[2] / "docs"
SPHERE_COUNTS = (8, 32, 64)  # spheres per Panda mesh element measured besides the spheres level's own
LINES: list[str] = []


def emit(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


class Robot:
    """One robot's checker at every fidelity level, and at ``spheres`` with each of ``sphere_counts`` spheres per
    mesh element besides the level's own (named ``spheres (N)``); link poses come from numpy FK, one row per
    URDF link."""

    def __init__(self, urdf: Path, base: str, fixed: tuple[str, ...], sphere_counts: tuple[int, ...] = ()) -> None:
        self.urdf, self.kin = urdf, UrdfKinematics(urdf)
        models = {f: RobotCollisionModel.from_urdf(urdf, f, self.kin.links) for f in FIDELITY_LEVELS}
        for n in sphere_counts:
            shapes = build_link_shapes(load_collision_elements(urdf), "spheres", n_spheres=n)
            models[f"spheres ({n})"] = RobotCollisionModel(shapes, self.kin.links, acm=load_acm(urdf, "spheres"))
        self.levels = tuple(models)
        self.checkers = {f: CollisionChecker(m, base, clearance_range=RANGE, fixed_links=fixed)
                         for f, m in models.items()}

    def poses(self, q: np.ndarray, base: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Link positions (n, L, 3) and rotations (n, L, 3, 3) for joints q (n, J) and base frames (n, 4, 4)."""
        frames = self.kin.forward(q)
        t = np.stack([frames[link] for link in self.kin.links], axis=1)
        if base is not None:
            t = base[:, None] @ t
        return t[..., :3, 3].copy(), t[..., :3, :3].copy()

    def clearance(self, level: str, pos: np.ndarray, rot: np.ndarray) -> float:
        checker = self.checkers[level]
        checker.model.sync(pos, rot)
        return float(checker.clearance()[0].min())


def near_configs(robot: Robot, scenes: list[tuple[Obstacle, ...]], per_scene: int, draw) -> list[dict]:
    """Per scene: configurations ``draw(n) -> (q, base)`` whose mesh clearance lies in (0, NEAR]."""
    out, mesh = [], robot.checkers["mesh"]
    for obstacles in scenes:
        mesh.set_scene(obstacles, [])
        keep: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        while len(keep) < per_scene:
            q, base = draw(4 * per_scene)
            pos, rot = robot.poses(q, base)
            keep += [(q[i], pos[i], rot[i]) for i in range(len(q))
                     if 0.0 < robot.clearance("mesh", pos[i], rot[i]) <= NEAR]
        keep = keep[:per_scene]
        out.append({"obstacles": obstacles, "q": np.array([k[0] for k in keep]),
                    "pos": np.array([k[1] for k in keep]), "rot": np.array([k[2] for k in keep])})
    return out


def sample_panda(panda: Robot, rng: np.random.Generator, n_scenes: int, per_scene: int) -> list[dict]:
    """Panda configurations near obstacles: q uniform within the joint limits, seeded tabletop scenes + the table."""
    lo, hi = panda.kin.lower, panda.kin.upper

    def draw(n: int) -> tuple[np.ndarray, None]:
        q = rng.uniform(lo, hi, size=(n, len(lo)))
        q[:, 7:] = FINGER_OPENING
        return q, None

    scenes = [(*sample_reach_scene(rng, TableSpec(), READY, SHOULDER, REACH_RADIUS).obstacles, TABLE)
              for _ in range(n_scenes)]
    return near_configs(panda, scenes, per_scene, draw)


def diffbot_robot() -> Robot:
    return Robot(DiffDriveRobot().urdf_path, "base_link", ())


def sample_diffbot(diffbot: Robot, rng: np.random.Generator, n_scenes: int, per_scene: int) -> list[dict]:
    """Diffbot floor poses near obstacles in seeded clutter scenes plus the arena walls."""
    walls, half = arena_walls(6.0, 0.5, 0.1), 3.0

    def draw(n: int) -> tuple[np.ndarray, np.ndarray]:
        x, y, yaw = rng.uniform(-half, half, n), rng.uniform(-half, half, n), rng.uniform(-np.pi, np.pi, n)
        base = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        base[:, 0, 0], base[:, 0, 1], base[:, 1, 0], base[:, 1, 1] = np.cos(yaw), -np.sin(yaw), np.sin(yaw), np.cos(yaw)
        base[:, :3, 3] = np.stack([x, y, np.full(n, DIFFBOT_Z)], axis=1)
        return np.zeros((n, len(diffbot.kin.joints))), base

    scenes = [(*sample_scene(rng, ClutterSpec(), robot_radius=0.17).obstacles, *walls) for _ in range(n_scenes)]
    return near_configs(diffbot, scenes, per_scene, draw)


def fidelity_table(name: str, robot: Robot, cases: list[dict], self_query: bool) -> dict[str, dict]:
    """Per level: env and self query times (us) and min clearances, levels interleaved scene by scene."""
    res = {f: {"env": [], "self": [], "d": []} for f in robot.levels}
    for s, case in enumerate(cases):
        for level in np.roll(robot.levels, s):  # rotate the order: no level always runs first
            r = res[level]
            robot.checkers[level].set_scene(case["obstacles"], [])
            for pos, rot in zip(case["pos"], case["rot"]):
                t0 = time.perf_counter()
                r["d"].append(robot.clearance(level, pos, rot))  # sync + clearance
                t1 = time.perf_counter()
                if self_query:
                    robot.checkers[level].model.self_clearance()
                r["env"].append(t1 - t0)
                r["self"].append(time.perf_counter() - t1)
    mesh = np.array(res["mesh"]["d"])
    emit(f"\n### {name}: {len(mesh)} configurations near obstacles (mesh clearance in (0, {NEAR}] m), "
         f"{len(cases)} scenes\n")
    emit(table_header("level", "env query (us)", "self query (us)", "speed vs mesh", "mean abs err (mm)", "p95 (mm)",
                      "max (mm)", "conservative"))
    mesh_us = 1e6 * np.mean(res["mesh"]["env"])
    for level in robot.levels:
        r = res[level]
        r["env_us"], err = 1e6 * float(np.mean(r["env"])), np.array(r["d"]) - mesh
        r["err_mm"] = 1e3 * float(np.abs(err).mean())
        self_us = f"{1e6 * np.mean(r['self']):.0f}" if self_query else "n/a (no ACM pairs)"
        cons = "-" if level == "mesh" else f"{np.mean(err < -1e-6):.0%}"
        emit(f"| {level} | {r['env_us']:.0f} | {self_us} | {mesh_us / r['env_us']:.2f}x | {r['err_mm']:.2f} | "
             f"{1e3 * np.percentile(np.abs(err), 95):.2f} | {1e3 * np.abs(err).max():.2f} | {cons} |")
    return res


class BulletWorld:
    """A DIRECT client with the Panda (fixed base) and the obstacles as static bodies."""

    def __init__(self, urdf: Path) -> None:
        with quiet_c_output():
            self.cid = pb.connect(pb.DIRECT)
            self.robot = pb.loadURDF(str(urdf), useFixedBase=True, physicsClientId=self.cid)
        info = [pb.getJointInfo(self.robot, j, physicsClientId=self.cid) for j in
                range(pb.getNumJoints(self.robot, physicsClientId=self.cid))]
        self.joint = {i[1].decode(): i[0] for i in info}
        self.collision_links = [i[0] for i in info
                                if pb.getCollisionShapeData(self.robot, i[0], physicsClientId=self.cid)]
        self.bodies: list[int] = []

    def set_scene(self, obstacles: list[Obstacle]) -> None:
        for b in self.bodies:
            pb.removeBody(b, physicsClientId=self.cid)
        self.bodies = []
        for o in obstacles:
            shape = (pb.createCollisionShape(pb.GEOM_CYLINDER, radius=o.radius, height=o.size[2],
                                             physicsClientId=self.cid)
                     if o.shape == "cylinder" else
                     pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.5 * s for s in o.size],
                                             physicsClientId=self.cid))
            quat = pb.getQuaternionFromEuler((0.0, 0.0, o.yaw))
            self.bodies.append(pb.createMultiBody(0.0, shape, basePosition=o.centre, baseOrientation=quat,
                                                  physicsClientId=self.cid))
        self.body_set = frozenset(self.bodies)

    def set_joints(self, q: np.ndarray, names: list[str]) -> None:
        for name, value in zip(names, q):
            pb.resetJointState(self.robot, self.joint[name], float(value), physicsClientId=self.cid)

    def clearance(self, bodies=None) -> float:
        """Minimum signed distance from the moving links to ``bodies`` (all obstacles by default), capped at RANGE."""
        best = RANGE
        for b in self.bodies if bodies is None else bodies:
            for p in pb.getClosestPoints(self.robot, b, RANGE, physicsClientId=self.cid):
                if p[3] != -1 and p[8] < best:
                    best = p[8]
        return best

    def clearance_broadphase(self) -> float:
        """The same, for the obstacles whose AABB overlaps a moving link's AABB grown by RANGE."""
        near: set[int] = set()
        for link in self.collision_links:
            low, high = pb.getAABB(self.robot, link, physicsClientId=self.cid)
            hits = pb.getOverlappingObjects(np.subtract(low, RANGE), np.add(high, RANGE), physicsClientId=self.cid)
            near.update(b for b, _ in hits or () if b in self.body_set)
        return self.clearance(near)


def pybullet_table(panda: Robot, cases: list[dict], fcl_res: dict) -> dict[str, float]:
    world, names = BulletWorld(panda.urdf), [j.name for j in panda.kin.joints]
    res: dict[str, list[float]] = {k: [] for k in ("loop", "broad", "convex", "mesh", "d_loop", "d_broad")}
    methods = {"loop": lambda p, r: world.clearance(), "broad": lambda p, r: world.clearance_broadphase(),
               "convex": lambda p, r: panda.clearance("convex", p, r),
               "mesh": lambda p, r: panda.clearance("mesh", p, r)}
    for case in cases:
        world.set_scene(list(case["obstacles"]))
        for level in ("convex", "mesh"):
            panda.checkers[level].set_scene(case["obstacles"], [])
        for q, pos, rot in zip(case["q"], case["pos"], case["rot"]):
            world.set_joints(q, names)
            for key, fn in methods.items():
                t0 = time.perf_counter()
                d = fn(pos, rot)
                res[key].append(time.perf_counter() - t0)
                if key in ("loop", "broad"):
                    res[f"d_{key}"].append(d)
    pb.disconnect(world.cid)
    mesh = np.array(fcl_res["mesh"]["d"])
    loop_us = 1e6 * np.mean(res["loop"])
    emit(f"\n### Panda: FCL against pybullet getClosestPoints, same {len(mesh)} configurations "
         f"(distance error against FCL mesh)\n")
    emit(table_header("method", "us per query", "pybullet loop time / this", "mean abs err (mm)", "mean signed (mm)",
                      "p95 (mm)", "max (mm)"))
    out = {}
    for key, label, d in (("loop", "pybullet getClosestPoints, every obstacle", res["d_loop"]),
                          ("broad", "pybullet, getOverlappingObjects first", res["d_broad"]),
                          ("convex", "FCL convex (sync + tree)", fcl_res["convex"]["d"]),
                          ("mesh", "FCL mesh (sync + tree)", fcl_res["mesh"]["d"])):
        us, err = 1e6 * np.mean(res[key]), np.array(d) - mesh
        out[key], out[f"{key}_err_mm"] = us, 1e3 * float(np.abs(err).mean())
        emit(f"| {label} | {us:.0f} | {loop_us / us:.1f}x | {out[f'{key}_err_mm']:.2f} | {1e3 * err.mean():+.2f} | "
             f"{1e3 * np.percentile(np.abs(err), 95):.2f} | {1e3 * np.abs(err).max():.2f} |")
    ratio = out["loop"] / out["convex"]
    emit(f"\nTarget FCL >= 5x faster than pybullet over all obstacles: {ratio:.1f}x (convex), "
         f"{out['loop'] / out['mesh']:.1f}x (mesh): {'met' if ratio >= 5 else 'NOT met'}")
    return out


def brute_force(model: RobotCollisionModel, moving: list[int], objects: list, pos: np.ndarray,
                rot: np.ndarray) -> float:
    """Minimum signed distance over every (moving shape, obstacle) pair, capped at RANGE; ``moving`` holds shape
    indices. Each pair is asked as the checker asks (:func:`signed_distance`, a mesh's hull answering in overlap):
    FCL's raw signed query aborts the process on some touching poses."""
    model.sync(pos, rot)
    return min(RANGE, min(signed_distance(model.objects[i], b, model.solid_objects[i])[0]
                          for i in moving for b in objects))


def scaling_table(panda: Robot, sizes: list[int], n_configs: int, budget_s: float) -> None:
    rng = np.random.default_rng(3)
    checker, world = panda.checkers["convex"], BulletWorld(panda.urdf)
    names = [j.name for j in panda.kin.joints]
    moving = [i for i, s in enumerate(checker.model.shapes) if s.link in checker.links]
    emit("\n### Broad phase: Panda (convex), N boxes of 5-15 cm over a square of side 1.5 sqrt(N/10) m, bottoms at "
         "z in [0, 0.9] m (fixed density); us per clearance query (n = queries timed)\n")
    emit(table_header("N obstacles", "checker (bounds, then FCL)", "brute force fcl.distance", "pybullet loop",
                      "pybullet broad phase", "checker vs brute max diff (mm)"))
    tree_us: dict[int, float] = {}
    last: dict[str, tuple[int, float]] = {}
    for n in sizes:
        side = 1.5 * np.sqrt(n / 10)
        obstacles = [Obstacle("box", tuple(map(float, rng.uniform(0.05, 0.15, 3))),
                              tuple(map(float, rng.uniform(-side / 2, side / 2, 2))),
                              float(rng.uniform(-np.pi, np.pi)), float(rng.uniform(0.0, 0.9))) for _ in range(n)]
        checker.set_scene(obstacles, [])
        objects = [obstacle_object(o) for o in obstacles]
        with quiet_c_output():
            world.set_scene(obstacles)
        q = rng.uniform(panda.kin.lower, panda.kin.upper, size=(n_configs, len(names)))
        q[:, 7:] = FINGER_OPENING
        pos, rot = panda.poses(q)
        methods = {"tree": lambda p, r: panda.clearance("convex", p, r),
                   "brute": partial(brute_force, checker.model, moving, objects),
                   "loop": lambda p, r: world.clearance(), "broad": lambda p, r: world.clearance_broadphase()}
        times: dict[str, list[float]] = {m: [] for m in methods}
        found: dict[str, list[float]] = {m: [] for m in methods}
        skip = {m for m, (n0, us) in last.items() if us * 1e-6 * n / n0 > SKIP_S}
        for i in range(n_configs):
            world.set_joints(q[i], names)
            for m, fn in methods.items():
                if m in skip or (times[m] and sum(times[m]) > budget_s):
                    continue
                t0 = time.perf_counter()
                found[m].append(fn(pos[i], rot[i]))
                times[m].append(time.perf_counter() - t0)
        cells = {}
        for m in methods:
            if m in skip:
                n0, us = last[m]
                cells[m] = f"~{us * n / n0:,.0f} (extrapolated)"
            else:
                us = 1e6 * float(np.mean(times[m]))
                last[m], cells[m] = (n, us), f"{us:,.0f} (n={len(times[m])})"
        tree_us[n] = 1e6 * float(np.mean(times["tree"]))
        k = min(len(found["tree"]), len(found["brute"]))
        diff = f"{1e3 * np.abs(np.subtract(found['tree'][:k], found['brute'][:k])).max():.3f}" if k else "-"
        emit(f"| {n:,} | {cells['tree']} | {cells['brute']} | {cells['loop']} | {cells['broad']} | {diff} |")
    pb.disconnect(world.cid)
    if 100 in tree_us and 10000 in tree_us:
        ratio = tree_us[10000] / tree_us[100]
        emit(f"\nChecker cost at 10,000 / at 100 obstacles: {ratio:.2f}x "
             f"(target <= 3x: {'met' if ratio <= 3 else 'NOT met'})")


def env_table(rounds: int, steps: int) -> None:
    envs = {f"ClutterReach-v1 ({f})": gym.make("ClutterReach-v1", collision_fidelity=f) for f in FIDELITY_LEVELS}
    with quiet_c_output():
        import panda_gym  # noqa: F401

        envs["PandaReach-v3 (panda-gym)"] = gym.make("PandaReach-v3")
    rng = np.random.default_rng(0)
    for env in envs.values():
        env.reset(seed=0)

    def block(env) -> float:  # steps/s in env.step (resets not counted)
        actions = rng.uniform(-1, 1, size=(steps, *env.action_space.shape)).astype(np.float32)
        return steps / run_block(env, actions)[0]

    rates = alternating_rounds({name: partial(block, env) for name, env in envs.items()}, rounds)
    peer = statistics.median(rates["PandaReach-v3 (panda-gym)"])
    emit(f"\n### Env throughput: random actions, {rounds} alternating rounds of {steps} steps, medians\n")
    emit(table_header("env", "steps/s", "vs PandaReach-v3"))
    for name, r in rates.items():
        emit(f"| {name} | {statistics.median(r):,.0f} | {statistics.median(r) / peer:.2f}x |")
    for env in envs.values():
        env.close()


def plot(results: dict[str, dict], bullet: dict[str, float], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for (name, res), marker in zip(results.items(), "os"):
        x, y = [res[f]["env_us"] for f in FIDELITY_LEVELS], [res[f]["err_mm"] for f in FIDELITY_LEVELS]
        ax.plot(x, y, marker=marker, linestyle=":", label=name)
        labels: dict[float, list] = {}  # one label for levels with the same error (the diffbot's primitives)
        for f, xi, yi in zip(FIDELITY_LEVELS, x, y):
            labels.setdefault(round(yi, 2), [[], xi, yi])[0].append(f)
        for names, xi, yi in labels.values():
            ax.annotate(" = ".join(names), (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.plot([bullet["loop"]], [bullet["loop_err_mm"]], "*", markersize=12, label="Panda, pybullet getClosestPoints")
    ax.set_xscale("log")
    ax.set_xlabel("time per environment clearance query (us, log)")
    ax.set_ylabel("mean |min clearance - mesh| (mm)")
    ax.set_title("Collision fidelity: cost against error (near obstacles)")
    ax.legend(fontsize=8)
    save_figure(fig, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer samples (under a minute)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    quick, rng, t_start = args.quick, np.random.default_rng(args.seed), time.perf_counter()
    n_scenes, per_scene = (6, 50) if quick else (30, 100)

    emit(f"## Collision fidelity benchmark{' (--quick)' if quick else ''}\n\nClearance range {RANGE} m; "
         "times are means per query in one process, competitors interleaved; compare ratios.")
    panda, diffbot = Robot(PandaArm().urdf_path, "panda_link0", ("panda_link0",), SPHERE_COUNTS), diffbot_robot()
    panda_cases, diffbot_cases = sample_panda(panda, rng, n_scenes, per_scene), sample_diffbot(diffbot, rng, n_scenes,
                                                                                                 per_scene)
    emit(f"\n(sampling the configurations: {time.perf_counter() - t_start:.0f} s)")

    results = {"Panda": fidelity_table("Panda", panda, panda_cases, self_query=True),
               "diffbot": fidelity_table("diffbot", diffbot, diffbot_cases, self_query=False)}
    emit("\nenv query = model.sync + checker.clearance over the moving links; conservative = share of configurations "
         "where the level reports over 1 um less clearance than mesh; the diffbot's geometry is primitives only, so "
         "primitive = convex = mesh there.")
    bullet = pybullet_table(panda, panda_cases, results["Panda"])
    sizes = [10, 100, 1000] if quick else [10, 100, 1000, 10000]
    scaling_table(panda, sizes, n_configs=10 if quick else 40, budget_s=0.5 if quick else 4.0)
    env_table(rounds=2 if quick else 4, steps=200 if quick else 500)

    DOCS.mkdir(exist_ok=True)
    plot(results, bullet, DOCS / "collision_fidelity.png")
    emit(f"\nTotal wall time {time.perf_counter() - t_start:.0f} s; figure docs/collision_fidelity.png")
    (DOCS / "collision_fidelity.md").write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
