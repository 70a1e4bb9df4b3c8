"""One speed-against-error report: for every choice a user makes, a table and a Pareto plot, the default marked and
justified by its row.

Choices: collision fidelity (every level, and sphere counts; Panda and diffbot), physics rate and solver iterations,
``physics="auto"`` against the fixed defaults on scenes with and without stacks, LIDAR ray count, LIDAR ray caster,
camera image size, depth camera renderer, noise profile, ClutterFly-v1's aerodynamics, each env's dynamics. Each
section comes from the benchmark module that owns the measurement (``collision_fidelity``, ``physics_rate``,
``stacking``, ``lidar_resolution``, ``cylinder_rays``, ``camera_resolution``, ``camera_renderer``, ``noise_cost``,
``aero_cost``, ``dynamics.choices``), and a headline from ``throughput`` opens the report.
Writes ``docs/speed-vs-error.md`` and one plot per choice in ``docs/speed-vs-error/``.

    python -m benchmarks.speed_vs_error            # or: python3 tasks.py bench (about 3 min on 2 cores)
    python -m benchmarks.speed_vs_error --quick    # fewer samples (under a minute)
    python -m benchmarks.speed_vs_error --sections lidar-rays aero --out out/report    # some sections, elsewhere
"""

from __future__ import annotations

import argparse
import contextlib
import io
import platform
import time
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np

from benchmarks.choice import Choice, Row, plot_choice
from benchmarks.dynamics.choices import fly_choice, nav_choice, reach_choice
from benchmarks.fidelity import camera_renderer, camera_resolution, collision_fidelity, cylinder_rays, lidar_resolution
from benchmarks.hard_cases import stacking
from benchmarks.harness import table_header
from benchmarks.speed import aero_cost, noise_cost, physics_rate, throughput
from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.util.atomic import write_text_atomically
from clutter_gym.util.machine import machine_state

DOCS = Path(__file__).resolve().parents[1] / "docs"
HEADLINE = "headline"  # the section that opens the report: the default step against its floor and a peer
REACH_DEFAULT, NAV_DEFAULT = "convex", "primitive"  # ClutterReach-v1's and ClutterNav-v1's collision_fidelity
NAV_MARGIN_MM = 100.0  # ClutterNav-v1's clearance_margin


def fidelity_choices(quick: bool, seed: int) -> list[Choice]:
    """Panda and diffbot: env clearance query time against the min-clearance error against ``mesh``."""
    rng = np.random.default_rng(seed)
    n_scenes, per_scene = (4, 40) if quick else (30, 100)
    cf = collision_fidelity
    panda = cf.Robot(cf.PandaArm().urdf_path, "panda_link0", ("panda_link0",), cf.SPHERE_COUNTS)
    diffbot = cf.diffbot_robot()
    with contextlib.redirect_stdout(io.StringIO()):  # the module prints its own tables
        panda_cases = cf.sample_panda(panda, rng, n_scenes, per_scene)
        diffbot_cases = cf.sample_diffbot(diffbot, rng, n_scenes, per_scene)
        panda_res = cf.fidelity_table("Panda", panda, panda_cases, self_query=False)
        diffbot_res = cf.fidelity_table("diffbot", diffbot, diffbot_cases, self_query=False)
        bullet = cf.pybullet_table(panda, panda_cases, panda_res)
    n = sum(len(c["q"]) for c in panda_cases)
    method = (f"{n} configurations per robot whose `mesh` clearance is in (0, {cf.NEAR}] m, in seeded scenes "
              f"(`python -m benchmarks.fidelity.collision_fidelity` has the full tables). Speed: one environment "
              f"clearance query (`model.sync` + `checker.clearance`, range {cf.RANGE} m). Error: mean |min clearance - "
              f"mesh|.")

    def rows(res: dict, default: str) -> list[Row]:
        out = []
        for level in res:
            r = res[level]
            err = np.abs(np.array(r["d"]) - np.array(res["mesh"]["d"]))
            out.append(Row(level, r["env_us"], r["err_mm"], level == default,
                           {"p95 (mm)": 1e3 * float(np.percentile(err, 95)), "max (mm)": 1e3 * float(err.max())}))
        return out

    panda_rows = rows(panda_res, REACH_DEFAULT)
    panda_rows.append(Row("pybullet getClosestPoints (reference, not a level)", bullet["loop"], bullet["loop_err_mm"],
                          False, {}, selectable=False))
    by = {r.label: r for r in panda_rows}
    c, mesh, spheres = by[REACH_DEFAULT], by["mesh"], by["spheres"]
    panda_why = (f"`{REACH_DEFAULT}` is ClutterReach-v1's default: {c.error:.2f} mm mean error at {c.speed:.0f} us, "
                 f"{mesh.speed / c.speed:.1f}x cheaper than `mesh` ({mesh.speed:.0f} us), and it is the geometry "
                 f"pybullet simulates, so FCL and pybullet agree on contact. The sphere levels are not cheaper enough "
                 f"to pay for their error: `spheres` (16 per link) costs {spheres.speed:.0f} us for "
                 f"{spheres.error:.1f} mm. `auto` adds `mesh` only where a hull is off its mesh (one Panda link).")
    nav_rows = rows(diffbot_res, NAV_DEFAULT)
    by = {r.label: r for r in nav_rows}
    p, sphere = by[NAV_DEFAULT], by["sphere"]
    nav_why = (f"`{NAV_DEFAULT}` is ClutterNav-v1's default: the diffbot is built from primitives, so this level is "
               f"exact ({p.error:.2f} mm against `mesh`) at {p.speed:.0f} us; `convex` and `mesh` answer the same "
               f"shapes. `sphere` costs {sphere.speed:.0f} us for {sphere.error:.0f} mm of error.")
    fidelity = "`collision_fidelity`, sphere counts as `spheres (N)`"
    return [Choice("fidelity-panda", "Collision fidelity: Panda (ClutterReach-v1)", fidelity, "query (us)", False,
                   "mean error (mm)", panda_rows, method, panda_why),
            Choice("fidelity-diffbot", "Collision fidelity: diffbot (ClutterNav-v1)", fidelity, "query (us)", False,
                   "mean error (mm)", nav_rows, method, nav_why)]


def physics_choice() -> Choice:
    settings, gap, length = physics_rate.rows()
    rows = [Row(f"{r['hz']:.0f} Hz, {r['iterations']} it.", r["rate"], r["error_mm"], r["default"],
                {"% of path": r["error_pct"], "wall penetration (mm)": r["penetration_mm"]}) for r in settings]
    d = next(r for r in rows if r.default)
    fine = min(r.extra["wall penetration (mm)"] for r in rows)
    coarser = [r for r in rows if r.speed > d.speed]
    method = (f"ClutterNav-v1 without sensors driven by 8 s of slalom commands ({length:.2f} m); error: the largest "
              f"distance from a {physics_rate.REFERENCE[0]:.0f} Hz / {physics_rate.REFERENCE[1]}-iteration reference "
              f"trajectory (the reference itself is {gap:.1f} mm from {physics_rate.REFERENCE_CHECK[0]:.0f} Hz). Wall "
              f"penetration: the deepest FCL contact while driving into a wall at full speed for 3 s.")
    why = (f"{d.label} is the fastest setting whose contact stays as stiff as the finest ones' "
           f"({d.extra['wall penetration (mm)']:.3f} mm into a wall against {fine:.3f} mm), at {d.speed:,.0f} "
           f"steps/s. The trajectory error is not monotone in the rate (heading errors of either sign accumulate "
           f"over the path) and stays within a few per cent of the path at every setting.")
    if coarser:
        r = coarser[0]
        why += (f" {r.label} runs {r.speed / d.speed:.2f}x faster but lets the robot "
                f"{r.extra['wall penetration (mm)'] / d.extra['wall penetration (mm)']:.0f}x deeper into the wall.")
    return Choice("physics", "Physics rate and solver iterations", "`physics_hz`, `solver_iterations`", "steps/s",
                  True, "trajectory error (mm)", rows, method, why)


def auto_physics_choice(quick: bool) -> Choice:
    """``physics="auto"`` against the fixed defaults: the stacking benchmark's scenes, and a generated layout."""
    seconds = 10.0 if quick else 30.0
    rows = []
    for label, n, masses in stacking.AUTO_SCENES:
        held = {}
        for physics in ("fixed", "auto", "fixed", "auto"):  # alternating; the rate is each one's best of two
            r = stacking.hold(n, 120.0, 10, seconds, masses, physics)
            best = held.get(physics, r)
            held[physics] = {**r, "steps_per_s": max(r["steps_per_s"], best["steps_per_s"])}
        for physics, r in held.items():
            rows.append(Row(f"{label}: {physics} ({r['physics_hz']:.0f} Hz, {r['iterations']} it.)",
                            r["steps_per_s"], r["drift_mm"], physics == "auto", {"max tilt (deg)": r["tilt_deg"]},
                            selectable=False))
    rates, paths = {}, {}
    for physics in ("fixed", "auto", "fixed", "auto"):  # alternating, each its best of two
        rate, path = _generated_layout_run(physics, 200 if quick else 1000)
        rates[physics], paths[physics] = max(rates.get(physics, 0.0), rate), path
    gap = 1e3 * float(np.abs(paths["auto"] - paths["fixed"]).max())
    for physics in ("fixed", "auto"):
        rows.append(Row(f"generated layout: {physics}", rates[physics], gap if physics == "auto" else 0.0,
                        physics == "auto", selectable=False))
    method = (f"ClutterNav-v1 without sensors, from its fixed defaults (120 Hz, 10 iterations) with `physics` "
              f"\"fixed\" or \"auto\". Stacks and loads (`python -m benchmarks.hard_cases.stacking --auto-only`): "
              f"movable boxes held for {seconds:.0f} s of zero commands (steps/s: best of two alternating runs "
              f"each); error: the largest horizontal drift of any box from where it was placed, its largest tilt as "
              f"an extra column. A generated layout (seed 0, random commands, the robot driving into the "
              f"clutter): steps/s, best of two alternating runs each, and as error the largest distance between the "
              f"two runs' robot positions. Rows compare settings per scene, not across scenes, so none is on a "
              f"Pareto front.")
    fixed = {r.label.split(":")[0]: r for r in rows if ": fixed" in r.label}
    auto = {r.label.split(":")[0]: r for r in rows if ": auto" in r.label}
    held = [k for k in auto if auto[k].error <= 1.0 and auto[k].extra.get("max tilt (deg)", 0.0) <= 1.0]
    slow = [auto[k].speed / fixed[k].speed for k in auto if "Hz" in auto[k].label and "(120 Hz, 10 it.)" not in
            auto[k].label]
    same = auto["generated layout"].speed / fixed["generated layout"].speed
    why = (f"\"auto\" is the default of ClutterNav-v1 and ClutterReach-v1: {len(held)} of {len(auto)} scenes hold 1 mm "
           f"and 1 deg under it, each at the least of its tiers that holds the catalogue's cases; scenes that need "
           f"more run at {min(slow):.2f}-{max(slow):.2f}x the fixed rate, and a scene that needs nothing runs at the "
           f"defaults, bit for bit (the generated layout: {same:.2f}x the fixed rate, {gap:.3g} mm apart).")
    return Choice("auto-physics", "Physics chosen per scene (physics=\"auto\")", "`physics`", "steps/s", True,
                  "max drift (mm)", rows, method, why)


def _generated_layout_run(physics: str, steps: int) -> tuple[float, np.ndarray]:
    """Steps/s of ClutterNav-v1 on its seed-0 layout under seeded random commands, and the robot's path (steps, 3)."""
    env = gym.make("ClutterNav-v1", sensors=(), physics=physics)
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (steps, 2))
    path = np.empty((steps, 3))
    began = time.perf_counter()
    for k, action in enumerate(actions):
        env.step(action)
        path[k] = env.unwrapped.robot.state().position
    rate = steps / (time.perf_counter() - began)
    env.close()
    return rate, path


def lidar_choice(quick: bool, seed: int) -> Choice:
    measured = lidar_resolution.rows(200 if quick else 2000, seed)
    rows = [Row(f"{r['rays']} rays", r["scan_us"], r["mean_mm"], r["default"], {"p95 (mm)": r["p95_mm"]})
            for r in measured]
    d = next(r for r in rows if r.default)
    half = rows[rows.index(d) - 1]
    method = (f"The scripted navigator's poses in seeded layouts; speed: one clean scan (the default exact caster); "
              f"error: the nearest return less a {lidar_resolution.REFERENCE_RAYS}-ray scan's, i.e. how much closer "
              f"the nearest obstacle is than the scan says.")
    per_ray, fixed = np.polyfit([r["rays"] for r in measured], [r["scan_us"] for r in measured], 1)
    why = (f"{d.label}: p95 error {d.extra['p95 (mm)']:.0f} mm, {d.extra['p95 (mm)'] / NAV_MARGIN_MM:.0%} of the "
           f"{NAV_MARGIN_MM / 1000} m clearance margin ClutterNav-v1's reward acts on, at {d.speed:.0f} us per "
           f"scan; {half.label} take {half.speed / d.speed:.0%} of its time but miss by "
           f"{half.extra['p95 (mm)']:.0f} mm (p95). A scan costs about {fixed:.0f} us plus {per_ray:.2f} us a ray "
           f"(least squares over the rows).")
    return Choice("lidar-rays", "LIDAR ray count", "`n_rays`", "scan (us)", False, "mean error (mm)", rows, method,
                  why)


def cylinder_choice() -> Choice:
    rows = [Row(r["label"], r["scan_us"], r["max_mm"], r["default"], {"mean signed (mm)": r["mean_mm"]})
            for r in cylinder_rays.rows()]
    exact = next(r for r in rows if r.default)
    prism = next(r for r in rows if "collision shape" in r.label)
    method = ("Twenty cylinders (r = 0.2 m) around a 64-beam scan; error: the largest range error of 400 beams fanned "
              "across one cylinder, against the exact ray-circle intersection. pybullet casts against a cylinder's "
              "collision shape, which the envs build as a 64-gon prism.")
    why = (f"{exact.label}: exact to rounding ({exact.error:.1g} mm) and {prism.speed / exact.speed:.1f}x faster than "
           f"pybullet's rays on the envs' prisms ({prism.error:.2f} mm). pybullet's rays are the fallback in a world "
           f"holding shapes the caster does not model, and `lidar_caster=\"pybullet\"` asks for them.")
    return Choice("cylinders", "LIDAR ray caster (against cylinders)", "`lidar_caster`", "scan (us)", False,
                  "max error (mm)", rows, method, why)


def camera_choice(quick: bool, seed: int) -> Choice:
    measured = camera_resolution.rows(50 if quick else 400, seed)
    rows = [Row(f"{r['size']}x{r['size']}", r["frame_us"], r["mean_mm"], r["default"], {}) for r in measured]
    d = next(r for r in rows if r.default)
    ref = camera_resolution.REFERENCE_SIZE
    method = (f"The scripted navigator's poses with the RGB-D camera; speed: one RGB-D frame with TinyRenderer (the "
              f"default `camera_renderer`; `egl` needs a GPU and is not measured here); error: mean |depth - "
              f"{ref}x{ref} depth| at the reference's pixels.")
    why = (f"{d.label}: the input size of SB3's `NatureCNN` and of most pixel-based RL, {d.error:.0f} mm mean depth "
           f"error at {d.speed:,.0f} us a frame. The frame time grows with the pixel count, so halve the side for "
           f"about a quarter of the cost when a policy does not need the detail.")
    return Choice("camera-size", "Camera image size", "`camera_size`", "frame (us)", False, "mean depth error (mm)",
                  rows, method, why)


def renderer_choice(quick: bool, seed: int) -> Choice:
    measured = camera_renderer.rows(40 if quick else 200, seed)
    names = {"rays": "rays", "tiny": "tiny (TinyRenderer)"}
    rows = [Row(names[r["renderer"]], r["frame_us"], r["mean_mm"], r["default"],
                {"99th percentile (mm)": r["p99_mm"], "largest (mm)": r["max_mm"]}) for r in measured]
    rays, tiny = rows
    method = ("ClutterFly-v1's drone camera, 84x84 depth, at the poses of the scripted flyer's flights through "
              "seeded layouts; speed: one frame's CPU time; error: |depth - the exact depth| over the pixels either "
              "image sees, the exact depth being the ray cast through the same sample points (the ray caster is "
              "exact: its tests hold it to closed forms within 1e-12 m). `egl` needs a GPU and is not measured.")
    p99 = tiny.extra["99th percentile (mm)"]
    why = (f"rays, for a depth or segmentation camera among boxes and cylinders: exact and "
           f"{tiny.speed / rays.speed:.1f}x faster ({rays.speed:,.0f} against {tiny.speed:,.0f} us a frame). "
           f"TinyRenderer's polygon cylinders, float32 depth buffer and edge rules cost {tiny.error:.1f} mm on average "
           f"({p99:.0f} mm at the 99th percentile; the largest are pixels on silhouettes). Take `tiny` for rgb, or to "
           f"see robots, which the ray caster does not draw.")
    return Choice("camera-renderer", "Depth camera renderer (ClutterFly-v1)", "`camera_renderer`", "frame (us)", False,
                  "mean depth error (mm)", rows, method, why)


def noise_choice(quick: bool, seed: int) -> Choice:
    rates, shares = noise_cost.measure(2 if quick else 8, 500 if quick else 1000, seed)
    rows = []
    for name in PROFILE_NAMES:
        extra = {"step time vs none (%)": 100 * (rates["none"] / rates[name] - 1)}
        if name != "none":
            extra["noise code, share of the step (%)"] = 100 * shares[f"{name}, sensor noise only"]
        rows.append(Row(name, rates[name], 1e3 * noise_cost.lidar_deviation_m(name, 150 if quick else 300, seed),
                        name == "none", extra))
    worst = max(v for v in shares.values())
    method = ("ClutterNav-v1 random-walk steps under each profile as specified (its own sensor rates, action noise "
              "and dynamics randomisation); error: the mean absolute difference between the profile's LIDAR "
              "observation and the clean one on the same trajectory (the profile's sensor noise only). Here the "
              "error is the point: it is the gap to real sensors a profile models.")
    noisy = [rates[name] / rates["none"] for name in PROFILE_NAMES if name != "none"]
    why = (f"`none` is the default: the clean reference every profile is compared against. Noise is cheap: the noise "
           f"code itself is at most {worst:.0%} of a step, and the noisy profiles step at {min(noisy):.0%}-"
           f"{max(noisy):.0%} of `none`'s rate, so choose the profile by the robot you will deploy on, not by speed.")
    return Choice("noise", "Noise profile", "`noise`", "steps/s", True, "LIDAR deviation (mm)", rows, method, why)


def aero_choice(quick: bool) -> Choice:
    measured = aero_cost.rows(2 if quick else 8)
    flights = aero_cost.FLIGHTS
    spawn = measured[0]["spawn_height"]
    lift_low = f"hover lift at {1e3 * aero_cost.LOW_START_Z:.0f} mm (% of g)"
    lift_spawn = f"hover lift at {spawn:.1f} m (% of g)"
    rows = [Row(r["label"] + (" (reference)" if r["reference"] else ""), r["rate"], r["error_mm"], r["default"],
                {"mean error (mm)": r["mean_mm"], **{f"{f.name} max (mm)": r[f"{f.name}_mm"] for f in flights},
                 lift_low: 100 * r["lift_low"], lift_spawn: 100 * r["lift_spawn"]}) for r in measured]
    off, drag, ground, both = measured
    cruise, low = flights
    method = (f"ClutterFly-v1 without sensors, flown closed loop by the scripted position controller "
              f"(`CascadedFlyer`, aimed at the goal) through two flights in an empty volume: a cruise of "
              f"{np.linalg.norm(np.subtract(cruise.goal, cruise.start[:3])):.0f} m at {cruise.start[2]:.0f} m height "
              f"at up to {cruise.max_speed:.0f} m/s, and a low flight of "
              f"{np.linalg.norm(np.subtract(low.goal, low.start[:3])):.0f} m at {low.max_speed:.0f} m/s from a "
              f"start {1e3 * low.start[2]:.0f} mm up (just above the drone's bounding radius, the lowest start a scene "
              f"allows) to a hover {1e3 * low.goal[2]:.0f} mm up, {cruise.steps} and "
              f"{low.steps} steps including the arrival. Error: the largest distance of the base from the fullest "
              f"model's (`('drag', 'ground_effect')`) at equal steps over both flights (the mean and each "
              f"flight's largest as extra columns). Speed: steps per CPU-second of `env.step` over the same flights, "
              f"median of alternating rounds. Hover lift: the open-loop vertical acceleration of one control step of "
              f"the hover command from rest, as a share of g, at the low start and at the lowest height the scene "
              f"generator spawns at ({spawn:.1f} m), less that without `aero`. `python -m benchmarks.speed.aero_cost` "
              f"prints the table alone.")
    at = {r["label"]: {f.name: r[f"{f.name}_mm"] for f in flights} for r in measured}
    no_drag, no_ground = at[ground["label"]], at[drag["label"]]  # the rows that leave drag, ground effect out
    why = (f"Off is the default. At the heights the env spawns at (>= {spawn:.1f} m) ground effect lifts a hover "
           f"by {100 * ground['lift_spawn']:.3f}% of its weight, and leaving it out of the cruise moves the path by "
           f"{no_ground[cruise.name]:.2f} mm; turn it on for flight within a few rotor radii of the floor (take-off, "
           f"landing, skimming): at {1e3 * aero_cost.LOW_START_Z:.0f} mm it lifts a hover by "
           f"{100 * ground['lift_low']:.2f}%, and leaving it out of the low flight costs {no_ground[low.name]:.0f} mm "
           f"(with it, the position loop holds the hover higher). Drag is not negligible in closed loop: it slows "
           f"the position loop, which has no integrator, so without it the drone flies up to "
           f"{no_drag[cruise.name]:.0f} mm from the reference in the {cruise.max_speed:.0f} m/s cruise and "
           f"{no_drag[low.name]:.0f} mm at {low.max_speed:.0f} m/s. Steps per CPU-second against off: drag "
           f"{drag['rate'] / off['rate']:.2f}x, ground effect {ground['rate'] / off['rate']:.2f}x, both "
           f"{both['rate'] / off['rate']:.2f}x. Turn drag on when a policy or controller is to hold a speed or "
           f"transfer to a real Crazyflie; off keeps the plain rigid-body model the gym-pybullet-drones peer flies "
           f"by default.")
    return Choice("aero", "Aerodynamics (ClutterFly-v1)", "`aero`", "steps per CPU-s", True, "max error (mm)", rows,
                  method, why)


def headline(quick: bool, seed: int) -> list[str]:
    """The ClutterNav-v1 step against its raw pybullet floor and panda-gym's PandaReach-v3, and the reset time."""
    peer = throughput.make_peer()
    rounds = 2 if quick else 6
    nav = throughput.scenario("navigator", seed, rounds, 1000, peer)
    env = gym.make("ClutterNav-v1")
    resets = 1e3 * throughput.reset_times(env, 100 if quick else 500, warmup=200)
    env.close()
    lines = [f"ClutterNav-v1 at its defaults (64-beam LIDAR, IMU, FCL clearance, contacts and swept checks), "
             f"scripted navigator, {rounds} alternating blocks of 1,000 steps "
             f"(`python -m benchmarks.speed.throughput`):",
             "", f"- {nav['env']:,.0f} steps/s, {nav['ratio']:.2f}x the time of the raw pybullet work a step needs "
             f"(motors, physics, state reads, rays: {nav['floor']:,.0f} steps/s);"]
    if "peer" in nav:
        lines.append(f"- panda-gym PandaReach-v3 in the same alternation: {nav['peer']:,.0f} steps/s "
                     f"(ClutterNav-v1 runs {nav['env'] / nav['peer']:.2f}x its rate);")
    lines.append(f"- reset with a new layout: median {np.median(resets):.2f} ms.")
    return lines


def markdown(choice: Choice) -> list[str]:
    extras = list(dict.fromkeys(k for r in choice.rows for k in r.extra))
    front = choice.pareto()
    out = [f"## {choice.title}", "", f"Setting: {choice.setting}. {choice.method}", "",
           table_header("setting", choice.speed_label, choice.error_label, *extras, "Pareto front")]
    for r in choice.rows:
        label = f"**{r.label} (default)**" if r.default else r.label
        cells = [_cell(r.extra[k]) if k in r.extra else "" for k in extras]
        mark = "yes" if r.label in front else ("" if r.selectable else "n/a")
        out.append(f"| {label} | {_cell(r.speed)} | {_cell(r.error)} | {' | '.join(cells)}{' | ' if cells else ''}"
                   f"{mark} |")
    out += ["", f"**Why the default:** {choice.why}", "", f"![{choice.title}](speed-vs-error/{choice.key}.png)", ""]
    return out


def _cell(value: float) -> str:
    """Three significant figures below 1, one decimal below 100, whole numbers above."""
    if abs(value) < 1:
        return f"{value:.3g}"
    return f"{value:,.1f}" if abs(value) < 100 else f"{value:,.0f}"


def sections(quick: bool, seed: int) -> dict[str, Callable[[], list[Choice]]]:
    """The report's sections after the headline, by name: what measures each one's choices."""
    return {
        "fidelity": lambda: fidelity_choices(quick, seed),
        "physics": lambda: [physics_choice()],
        "auto-physics": lambda: [auto_physics_choice(quick)],
        "lidar-rays": lambda: [lidar_choice(quick, seed)],
        "cylinders": lambda: [cylinder_choice()],
        "camera-size": lambda: [camera_choice(quick, seed)],
        "camera-renderer": lambda: [renderer_choice(quick, seed)],
        "noise": lambda: [noise_choice(quick, seed)],
        "aero": lambda: [aero_choice(quick)],
        "dynamics": lambda: [nav_choice(quick), fly_choice(quick), reach_choice(quick)],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer samples per section (under a minute)")
    parser.add_argument("--seed", type=int, default=0)
    names = [HEADLINE, *sections(False, 0)]
    parser.add_argument("--sections", nargs="+", choices=names, default=names, metavar="NAME",
                        help="measure only these sections, of: " + ", ".join(names))
    parser.add_argument("--out", type=Path, default=DOCS,
                        help="folder of speed-vs-error.md and its plots (speed-vs-error/); default docs/")
    args = parser.parse_args()
    machine = machine_state()
    t0 = time.perf_counter()
    choices: list[Choice] = []
    for name, measure in sections(args.quick, args.seed).items():
        if name in args.sections:
            t = time.perf_counter()
            choices += measure()
            print(f"{name}: {time.perf_counter() - t:.0f} s", flush=True)
    options = (" --quick" if args.quick else "") + \
        ("" if args.sections == names else " --sections " + " ".join(args.sections))
    lines = ["# Speed against error", "",
             f"Written by `python3 tasks.py bench` (`python -m benchmarks.speed_vs_error{options}`, seed {args.seed}) "
             f"on {platform.machine()} with {platform.python_implementation()} {platform.python_version()}, "
             f"{machine}. Every "
             "speed figure is measured in one process beside the error it costs; "
             "compare ratios, as absolute times follow the machine. A choice's Pareto front is the settings no other "
             "is both faster and more accurate than.", ""]
    if HEADLINE in args.sections:
        lines += ["## The default step against its floor and a peer", "", *headline(args.quick, args.seed), ""]
    plots = args.out / "speed-vs-error"
    plots.mkdir(parents=True, exist_ok=True)
    for choice in choices:
        plot_choice(choice, plots / f"{choice.key}.png")
        lines += markdown(choice)
    lines += ["## Other benchmarks", "",
              "Not in this report because they answer other questions or run long: "
              "`benchmarks.speed.camera_throughput` (the RGB-D env against gym-pybullet-drones), "
              "`benchmarks.speed.vec_throughput` (vector envs), `benchmarks.hard_cases.memory` (memory over many "
              "resets), `benchmarks.fidelity.contact_agreement` and `benchmarks.fidelity.fcl_accuracy` (FCL against "
              "pybullet and closed forms), `benchmarks.learning.main_job` (PPO curves), "
              "`benchmarks.dynamics.reduced_error`, `flight_error` and `arm_error` (each env's reduced dynamics "
              "against full physics at full size, with the peers). Their results "
              "are in "
              "[benchmarks.md](benchmarks.md); those of `benchmarks.hard_cases.large_scenes` (resets and steps with up "
              "to 10,000 obstacles) in [design-notes.md](design-notes.md#large-scenes).", "",
              f"Total wall time: {time.perf_counter() - t0:.0f} s."]
    write_text_atomically(args.out / "speed-vs-error.md", "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
