"""Every measurable row of docs/hard-cases.md in one table: each case's error figure, the bound its test holds it
to, and the steps/s while it was measured.

Each case is a short version of the run its test or benchmark makes (fewer seconds, offsets or poses; ``--quick``
shorter still), through the same functions: the scenes and runs of :mod:`benchmarks.hard_cases.scenes`, the
``stacking``,
``tunneling`` and ``large_scenes`` benchmarks next to this one, and ``benchmarks.speed.physics_rate``. The rate
column says what it counts: env steps/s, physics ticks/s, or checker queries/s where a case places the robot instead
of stepping; it was measured on whatever else the machine was doing, so compare it within one run only. A bound of
"none" is a figure no test holds (a known failure at the defaults, or one the catalogue only reports).

    python -m benchmarks.hard_cases.catalogue [--quick] [--case NAME ...]
"""

from __future__ import annotations

import argparse
import contextlib
import multiprocessing
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases import large_scenes, stacking
from benchmarks.hard_cases.scenes import movable_clutter, scale, sensor_edges, tunneling
from benchmarks.hard_cases.scenes.penetration_depth import panda_depth_errors
from benchmarks.hard_cases.scenes.standstill import standstill_drift
from benchmarks.hard_cases.scenes.stepping import CONTROL_HZ
from benchmarks.hard_cases.scenes.wedging import wedge
from benchmarks.hard_cases.tunneling import OFFSETS, summary
from benchmarks.harness import table_header
from benchmarks.speed import physics_rate
from clutter_gym.sensors.lidar import Lidar, LidarConfig

ENV_STEPS, TICKS, QUERIES = "env steps/s", "physics ticks/s", "checker queries/s"


@dataclass(frozen=True)
class Row:
    """One case's line of the table.

    Attributes:
        case: the case's name in :data:`CASES`.
        figure: the error figure, in ``unit``.
        unit: the figure's unit ("mm", "m", "s", "%", "passes").
        bound: the largest figure its test (or the catalogue's target, per ``source``) allows, in ``unit``; None
            where nothing holds it.
        source: the test or target the bound comes from, or why there is none.
        rate: steps, ticks or queries per second while the case was measured.
        rate_unit: what ``rate`` counts (:data:`ENV_STEPS`, :data:`TICKS`, :data:`QUERIES`).
        settings: the settings and length of the run.
        detail: further figures of the same run.
    """

    case: str
    figure: float
    unit: str
    bound: float | None
    source: str
    rate: float
    rate_unit: str
    settings: str
    detail: str = ""

    @property
    def within(self) -> bool | None:
        """Whether the figure is within its bound (None: no bound)."""
        return None if self.bound is None else bool(self.figure <= self.bound)

    def markdown(self) -> str:
        figure = f"{self.figure:.3g} {self.unit}" + (f" ({self.detail})" if self.detail else "")
        if self.bound is None:
            bound = self.source
        else:
            bound = f"≤ {self.bound:.3g} {self.unit}, {'met' if self.within else '**missed**'} ({self.source})"
        return f"| {self.case} | {figure} | {bound} | {self.rate:,.0f} {self.rate_unit} | {self.settings} |"


@contextlib.contextmanager
def nav_maker() -> Iterator[Callable[..., gym.Env]]:
    """A ``make(**kwargs)`` of ClutterNav-v1 envs that closes every env it made when the block ends."""
    made: list[gym.Env] = []

    def make(**kwargs) -> gym.Env:
        made.append(gym.make("ClutterNav-v1", **kwargs))
        return made[-1]

    try:
        yield make
    finally:
        for env in made:
            env.close()


# ------------------------------------------------------------------------------------------------ standing still
def standstill(quick: bool) -> Row:
    """Drift of a base at zero command (after driving, at several headings), worst over the runs; mm."""
    seconds = 20.0
    runs = [(0.79, (0.5, 0.7)), (0.52, (0.0, 0.0))] if quick else \
        [(yaw, before) for yaw in (0.52, 0.79, 1.31) for before in ((0.0, 0.0), (0.5, 0.7))]
    env = gym.make("ClutterNav-v1", noise="none", max_episode_steps=10_000)
    try:
        results = [standstill_drift(env, yaw, before, seconds) for yaw, before in runs]
    finally:
        env.close()
    moved, turned = max(r[0] for r in results), max(r[1] for r in results)
    return Row("standstill", 1e3 * moved, "mm", 0.01, "test_standstill.py", float(np.mean([r[2] for r in results])),
               ENV_STEPS, f"defaults, noise none; {len(runs)} headings/histories, {seconds:g} s each",
               f"heading {1e3 * turned:.2g} mrad")


# ------------------------------------------------------------------------------------------------ wedging
def wedging(name: str, quick: bool) -> Row:
    """Deepest penetration of full command into a trap (:data:`benchmarks.hard_cases.scenes.wedging.WEDGES`); mm."""
    seconds = 20.0 if quick else 60.0
    run = wedge(name, seconds)
    return Row(f"wedging-{name}", 1e3 * run.penetration, "mm", 1.0, "test_wedging.py", run.steps_per_s, ENV_STEPS,
               f"defaults, noise none; {seconds:g} s full command",
               f"final speed {run.final_speed:.1g} m/s, {run.mismatched} contact/cost mismatches")


# ------------------------------------------------------------------------------------------------ tunneling
TUNNEL_SPEED, TUNNEL_WALL = 20.0, 0.01  # m/s, metres


def tunnel_starts(settings: tunneling.Settings, offsets: int) -> list[float]:
    """Start gaps (m) spread over one physics tick's travel at :data:`TUNNEL_SPEED`."""
    return [tunneling.GAP + k * TUNNEL_SPEED / settings.physics_hz / offsets for k in range(offsets)]


def tunnel_row(name: str, runs: list[tunneling.Run], bound: float | None, source: str, rate: float,
               rate_unit: str, settings: str) -> Row:
    """Passes the audit missed (passes neither a contact nor a swept hit flagged)."""
    s = summary(name, f"{TUNNEL_SPEED:g}", TUNNEL_WALL, runs, [])
    return Row(name, s["passes"] - s["passes_flagged"], "missed passes", bound, source, rate, rate_unit, settings,
               f"{s['passes']}/{s['runs']} runs passed, {s['passes_flagged']} flagged")


def tunneling_free(shape: str, rigid: bool, quick: bool) -> Row:
    """A free ``shape`` at 20 m/s at a 1 cm wall from several offsets, pybullet alone, audited."""
    offsets = OFFSETS if quick else 4 * OFFSETS
    nav = tunneling.make_nav_env()
    settings = tunneling.Settings.of(nav)
    nav.close()
    began = time.perf_counter()
    runs = [tunneling.free_body_run(settings, shape, TUNNEL_SPEED, TUNNEL_WALL, o, rigid=rigid, ccd=False)
            for o in tunnel_starts(settings, offsets)]
    ticks = offsets * tunneling.LAUNCH_STEPS * settings.substeps
    kind = "rigid body" if rigid else "multibody"
    return tunnel_row(f"tunneling-{shape}", runs, 0.0, "test_tunneling.py", ticks / (time.perf_counter() - began),
                      f"{TICKS} (Sim set-up included)",
                      f"{settings.physics_hz:.0f} Hz, swept check above {settings.swept_speed} m/s; {kind}, "
                      f"{TUNNEL_SPEED:g} m/s, 1 cm wall, {offsets} offsets")


def tunneling_nav(quick: bool) -> Row:
    """The nav robot launched at 20 m/s into a 1 cm wall from several offsets."""
    offsets = OFFSETS if quick else 4 * OFFSETS
    nav = tunneling.make_nav_env()
    try:
        settings = tunneling.Settings.of(nav)
        began = time.perf_counter()
        runs = [tunneling.nav_run(nav, TUNNEL_SPEED, TUNNEL_WALL, o, ccd=False)
                for o in tunnel_starts(settings, offsets)]
        rate = offsets * tunneling.LAUNCH_STEPS / (time.perf_counter() - began)
    finally:
        nav.close()
    return tunnel_row("tunneling-nav", runs, 0.0, "test_tunneling.py", rate, f"{ENV_STEPS} (resets included)",
                      f"defaults, no sensors; launched at {TUNNEL_SPEED:g} m/s, 1 cm wall, {offsets} offsets")


# ------------------------------------------------------------------------------------------------ movable clutter
def movable_settle(quick: bool) -> Row:
    """Largest move of settled tabletop clutter with the arm at rest; mm."""
    seconds = 10.0 if quick else 30.0
    moved, tilt, _, rate = movable_clutter.tabletop_creep(seconds)
    return Row("movable-settle", 1e3 * moved, "mm", 0.1, "test_movable_clutter.py", rate, ENV_STEPS,
               f"ClutterReach-v1, movable_obstacles 1, seed 2; {seconds:g} s after 0.5 s to settle",
               f"tilt {tilt:.2g} deg")


def movable_push(quick: bool) -> Row:
    """How far a pushed 1 kg box rests inside the wall it was driven into (its last second); mm."""
    env = gym.make("ClutterNav-v1", max_linear_speed=1.0)
    try:
        _, positions, rate = movable_clutter.push_box(env, 6.0)
    finally:
        env.close()
    inside = positions[:, 0] + movable_clutter.PUSH_BOX_HALF - movable_clutter.PUSH_WALL_FACE
    return Row("movable-push", 1e3 * max(0.0, float(inside[-20:].max())), "mm", 1.0, "test_movable_clutter.py",
               rate, ENV_STEPS, "ClutterNav-v1, max_linear_speed 1; 1 kg box driven into a wall, 6 s",
               f"{1e3 * float(inside.max()):.1f} mm in at the impact, 10 mm allowed")


# ------------------------------------------------------------------------------------------------ stacks and masses
def held(case: str, n: int, physics_hz: float, iterations: int, seconds: float, masses: tuple[float, ...],
         bound: float | None, source: str) -> Row:
    """:func:`stacking.hold`: the largest horizontal drift of any box; mm."""
    r = stacking.hold(n, physics_hz, iterations, seconds, masses)
    what = f"{n} boxes" if not masses else f"{masses[1]:g} kg on {masses[0]:g} kg"
    return Row(case, r["drift_mm"], "mm", bound, source, r["steps_per_s"], f"{ENV_STEPS} (no sensors)",
               f"{physics_hz:.0f} Hz, {iterations} iterations; {what}, {seconds:g} s",
               f"tilt {r['tilt_deg']:.2g} deg, top sank {r['sink_mm']:.2g} mm")


def stack(n: int, setting: tuple[float, int], bound: float | None, source: str, quick: bool) -> Row:
    """A stack of ``n`` 2 kg boxes held at ``setting`` (physics Hz, solver iterations)."""
    name = "default" if setting == (120.0, 10) else "held"
    return held(f"stack-{n}-{name}", n, *setting, 10.0 if quick else 30.0, (), bound, source)


def mass_ratio(case: str, masses: tuple[float, float], setting: tuple[float, int], bound: float | None,
               source: str, quick: bool) -> Row:
    """Two boxes (bottom, top kg) held 10 s at ``setting`` (physics Hz, solver iterations), ``quick`` or not (the
    hold is short already)."""
    return held(case, 2, *setting, 10.0, masses, bound, source)


# ------------------------------------------------------------------------------------------------ scale
def translated_pair(offset: float) -> tuple[scale.World, scale.World]:
    """The scale scene built at the origin and translated by (offset, offset, 0) m."""
    return scale.build(0.0), scale.build(offset)


def scale_poses(quick: bool) -> tuple[tuple[float, float, float], ...]:
    return scale.POSES[:40] if quick else scale.POSES


def scale_fcl(quick: bool) -> Row:
    """FCL clearance of the sphere shapes (casters), translated by 1e4 m minus untranslated; m."""
    origin, far = translated_pair(1e4)
    try:
        spheres = np.array([s.kind == "sphere" for s in origin.checker.model.shapes])
        poses, worst, began = scale_poses(quick), 0.0, time.perf_counter()
        for pose in poses:
            d0, d1 = scale.measure(origin, pose)[0], scale.measure(far, pose)[0]
            worst = max(worst, float(np.abs(d1[spheres] - d0[spheres]).max()))
        rate = 2 * len(poses) / (time.perf_counter() - began)
    finally:
        origin.sim.close()
        far.sim.close()
    return Row("scale-fcl", worst, "m", scale.ulps(1e4, scale.EXACT_ULPS), "20 ulp of 1e4, test_scale.py", rate,
               QUERIES, f"6 m scene at 1e4 m vs origin; {len(poses)} poses, primitive fidelity")


def scale_lidar(quick: bool) -> Row:
    """360-beam LIDAR ranges, translated by 1e4 m minus untranslated; m."""
    origin, far = translated_pair(1e4)
    lidar = Lidar(LidarConfig(n_rays=360, max_range=10.0))
    try:
        poses, worst, contact, began = scale_poses(quick), 0.0, 0.0, time.perf_counter()
        for pose in poses:
            (c0, r0, _), (c1, r1, _) = (scale.read_placed(world, pose, lidar) for world in (origin, far))
            worst = max(worst, float(np.abs(r1 - r0).max()))
            contact = max([contact] + [abs(c1[key][1] - d) for key, (_, d) in c0.items() if key in c1])
        rate = 2 * len(poses) / (time.perf_counter() - began)
    finally:
        origin.sim.close()
        far.sim.close()
    return Row("scale-lidar", worst, "m", scale.ulps(1e4, scale.RAY_ULPS), "500 ulp of 1e4, test_scale.py", rate,
               f"{QUERIES} (placement, contacts, check and scan)",
               f"6 m scene at 1e4 m vs origin; {len(poses)} poses", f"pybullet contact depths {contact:.2g} m")


def scale_drive(quick: bool) -> Row:
    """2 s of driving into a box: base position translated by 1e4 m minus untranslated, worst over the steps; m."""
    origin, far = translated_pair(1e4)
    try:
        began = time.perf_counter()
        runs = [scale.drive_into_box(world) for world in (origin, far)]
        rate = 2 * 40 * 6 / (time.perf_counter() - began)
    finally:
        origin.sim.close()
        far.sim.close()
    worst = max(float(np.abs(p1 - p0).max()) for (p0, *_), (p1, *_) in zip(*runs))
    return Row("scale-drive", worst, "m", scale.ulps(1e4, scale.POSE_ULPS), "20 ulp of 1e4, test_scale.py", rate,
               f"{TICKS} (with a check per 6)", "240 Hz, 40 control steps of full command into a box, 1e4 m vs origin")


def millimetre(quick: bool) -> Row:
    """Millimetre obstacles (2 mm rod, 1 mm cubes) 10 mm clear to 0.3 mm deep: FCL's signed distance against the
    closed form, worst over obstacles and gaps; m."""
    offsets = (1e4,) if quick else (0.0, 1e4)
    fcl, contact, queries, began = 0.0, 0.0, 0, time.perf_counter()
    for offset in offsets:
        for gap in (0.01, 0.002, 0.0, -0.0003):
            world = scale.build(offset, scale.millimetre_scene(gap))
            try:
                f, c = scale.millimetre_errors(world, gap)
            finally:
                world.sim.close()
            fcl, contact, queries = max(fcl, float(np.abs(f).max())), max([contact, *np.abs(c)]), queries + 1
    return Row("millimetre", fcl, "m", scale.MM_TOL, "test_scale.py", queries / (time.perf_counter() - began),
               f"scenes/s (built, placed, {len(scale.millimetre_scene(0.0))} signed distances)",
               f"gaps 10, 2, 0, -0.3 mm at {', '.join(f'{o:g}' for o in offsets)} m",
               f"pybullet contacts {contact:.2g} m, {scale.MM_CONTACT_TOL:g} allowed")


# ------------------------------------------------------------------------------------------------ large scenes
def large_scene(quick: bool) -> Row:
    """First reset of a 10,000-obstacle user scene, in a fresh process (:func:`large_scenes.measure`); s."""
    context = multiprocessing.get_context("spawn")
    queue = context.Queue()
    process = context.Process(target=large_scenes.measure, args=(10_000, False, queue))
    process.start()
    r = queue.get()
    process.join()
    return Row("large-scene", r["first"], "s", 1.0, "catalogue target, not a test", 1e3 / r["step"], ENV_STEPS,
               f"ClutterNav-v1, 30 m arena, 10,000 obstacles; median of {large_scenes.STEPS} steps",
               f"teardown {r['teardown']:.2f} s, physics alone {r['physics']:.1f} ms/step")


# ------------------------------------------------------------------------------------------------ sensor edges
def camera_far(quick: bool) -> Row:
    """Depth of the arena wall with the camera's far plane at 1000 m against the closed form, worst pixel of the
    frame at reset; mm. The rate is of the steps after it, at zero command."""
    steps = 10 if quick else 50
    first, settled, pixels, rate = sensor_edges.wall_depth_error(1000.0, steps)
    return Row("camera-far", 1e3 * first, "mm", 0.1, "test_sensor_edges.py", rate, f"{ENV_STEPS} (camera on)",
               f"84x64 depth camera, camera_far 1000 m; the reset frame, then {steps} steps at rest",
               f"{pixels} wall pixels; {1e3 * settled:.2f} mm once the base has settled 10 um, not in the closed form")


def imu_impact(quick: bool) -> Row:
    """Peak IMU acceleration through a stop from full speed against the mean deceleration over one control period
    (0.5 m/s in 0.05 s = 10 m/s^2); %."""
    with nav_maker() as make:
        readings, contacts, rate = sensor_edges.imu_impact(make)
    peak = float(np.abs(readings[:, 0]).max())
    expected = 0.5 * CONTROL_HZ
    return Row("imu-impact", 100 * abs(peak - expected) / expected, "%", 5.0, "test_sensor_edges.py", rate,
               f"{ENV_STEPS} (IMU only)", "noise none; full command into the wall from 0.3 m, 2 s",
               f"peak {peak:.2f} m/s^2, {contacts} steps in contact")


# ------------------------------------------------------------------------------------------------ contacts, physics
def penetration_depth(quick: bool) -> Row:
    """Contact depth against the signed distance on full-speed Panda steps, worst contact; m."""
    steps = 800 if quick else 3200
    worst, contacts, deep, rate = panda_depth_errors(steps)
    return Row("penetration-depth", worst, "m", 1e-9, "test_collision_layer.py", rate, ENV_STEPS,
               f"ClutterReach-v1, 10 obstacles, seed 0; {steps} full-speed random steps",
               f"{contacts} contacts, {deep} deeper than 1 mm")


def physics_rate_wall(physics_hz: float, iterations: int, quick: bool) -> Row:
    """Deepest FCL penetration driving at full speed into a wall for 3 s (:func:`physics_rate.wall_penetration_mm`);
    mm."""
    began = time.perf_counter()
    depth = physics_rate.wall_penetration_mm(physics_hz, iterations)
    rate = 3.0 * CONTROL_HZ / (time.perf_counter() - began)
    return Row(f"physics-rate-{physics_hz:.0f}", depth, "mm", None, "none: reported in speed-vs-error.md", rate,
               f"{ENV_STEPS} (no sensors; make and reset included)",
               f"{physics_hz:.0f} Hz, {iterations} iterations; 3 s full speed into a wall")


# ------------------------------------------------------------------------------------------------ the registry
CASES: dict[str, Callable[[bool], Row]] = {
    "standstill": standstill,
    "wedging-corner": lambda quick: wedging("corner", quick),
    "wedging-gap": lambda quick: wedging("gap", quick),
    "tunneling-ball": lambda quick: tunneling_free("ball", True, quick),
    "tunneling-cube": lambda quick: tunneling_free("cube", False, quick),
    "tunneling-nav": tunneling_nav,
    "movable-settle": movable_settle,
    "movable-push": movable_push,
    "stack-5-default": lambda quick: stack(5, (120.0, 10), None, "none: creeps at the defaults", quick),
    "stack-5-held": lambda quick: stack(5, (240.0, 100), 1.0, "test_movable_clutter.py", quick),
    "stack-10-default": lambda quick: stack(10, (120.0, 10), None, "none: falls at the defaults", quick),
    "stack-10-held": lambda quick: stack(10, (480.0, 200), 1.0, "catalogue's 1 mm, no test", quick),
    "mass-1t-on-1kg-default": lambda quick: mass_ratio("mass-1t-on-1kg-default", (1.0, 1e3), (120.0, 10), None,
                                                       "none: squirts out at the defaults", quick),
    "mass-1t-on-1kg-held": lambda quick: mass_ratio("mass-1t-on-1kg-held", (1.0, 1e3), (960.0, 200), 1.0,
                                                    "test_movable_clutter.py", quick),
    "mass-1kg-on-1t": lambda quick: mass_ratio("mass-1kg-on-1t", (1e3, 1.0), (120.0, 10), 1.0,
                                               "test_movable_clutter.py", quick),
    "scale-fcl": scale_fcl,
    "scale-lidar": scale_lidar,
    "scale-drive": scale_drive,
    "millimetre": millimetre,
    "large-scene": large_scene,
    "camera-far": camera_far,
    "imu-impact": imu_impact,
    "penetration-depth": penetration_depth,
    "physics-rate-120": lambda quick: physics_rate_wall(120.0, 10, quick),
    "physics-rate-60": lambda quick: physics_rate_wall(60.0, 10, quick),
}


def run_case(name: str, quick: bool) -> tuple[Row, float]:
    """Case ``name`` of :data:`CASES`: its row, and the wall-clock seconds it took."""
    began = time.perf_counter()
    row = CASES[name](quick)
    return row, time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="shorter runs (fewer seconds, offsets, poses)")
    parser.add_argument("--case", nargs="+", choices=list(CASES), default=list(CASES), metavar="NAME",
                        help="run only these cases, of: " + ", ".join(CASES))
    args = parser.parse_args()
    print(table_header("case", "error figure", "bound it is tested against", "steps/s", "settings"), flush=True)
    seconds, began = {}, time.perf_counter()
    for name in args.case:
        row, seconds[name] = run_case(name, args.quick)
        print(row.markdown(), flush=True)
    print(f"\n{len(seconds)} cases in {time.perf_counter() - began:.0f} s{' (--quick)' if args.quick else ''}: "
          + ", ".join(f"{name} {s:.1f} s" for name, s in seconds.items()))


if __name__ == "__main__":
    main()
