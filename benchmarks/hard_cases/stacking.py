"""How well movable clutter holds still: stacks of boxes, and a box on a box a thousand times lighter or heavier,
in ClutterNav-v1 at several physics rates and solver iteration counts, with the robot at rest, against the time
it costs.

A stack of ``n`` boxes (0.3 x 0.3 x 0.2 m, 2 kg each: ``benchmarks.hard_cases.scenes.movable_clutter.stack_scene``) is
placed exactly touching, as a user scene puts it. Bullet's sequential-impulse solver needs more iterations the
taller the stack (an impulse crosses one contact per iteration), so short stacks hold at settings where tall ones
creep or fall. Printed per setting: the largest
horizontal drift of any box and its largest tilt over the 30 s, how far the top box sank, and steps/s. The mass
ratios hold two boxes for 10 s: a heavy box on a light one is the solver's hard case (the light box's contacts
must carry a thousand times its weight), a light one on a heavy one its easy case. The last table holds the same
scenes at the env's defaults under ``physics="fixed"`` and under ``physics="auto"``, which picks the settings from
the scene (``clutter_gym.auto_physics``): what each costs and what it holds.

    python -m benchmarks.hard_cases.stacking [--seconds 30] [--auto-only]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.movable_clutter import stack_scene, tilt_degrees
from benchmarks.harness import table_header

#: (physics_hz, solver iterations)
SETTINGS = ((120.0, 10), (120.0, 50), (240.0, 50), (240.0, 100), (480.0, 100), (480.0, 200), (960.0, 100))


RATIOS = ((1.0, 1e3), (1.0, 1e2), (1e3, 1.0))  # (bottom, top) kg


#: The scenes of the fixed-against-auto table: (label, boxes, masses bottom first)
AUTO_SCENES = (("1 box", 1, ()), ("2 boxes", 2, ()), ("5 boxes", 5, ()), ("10 boxes", 10, ()),
               ("1 kg on 1 t", 2, (1e3, 1.0)), ("1 t on 1 kg", 2, (1.0, 1e3)))


def hold(n: int, physics_hz: float, iterations: int, seconds: float, masses: tuple[float, ...] = (),
         physics: str = "fixed") -> dict[str, float]:
    """Drift (mm), tilt (degrees) and sinking of the top box (mm) of an ``n``-box stack held for ``seconds``,
    steps/s, and the physics the episode ran at (``physics="auto"`` may raise ``physics_hz`` and ``iterations``)."""
    env = gym.make("ClutterNav-v1", physics_hz=physics_hz, solver_iterations=iterations, sensors=(), physics=physics)
    _, info = env.reset(seed=0, options={"scene": stack_scene(n, masses)})
    sim, bodies = env.unwrapped.sim, env.unwrapped.movable_bodies
    start, start_rotation = sim.obstacles.body_poses(bodies)
    drift, tilt, zero = 0.0, 0.0, np.zeros(2)
    steps = int(round(seconds * env.unwrapped.metadata["render_fps"]))
    began = time.perf_counter()
    for _ in range(steps):
        env.step(zero)
        position, rotation = sim.obstacles.body_poses(bodies)
        drift = max(drift, float(np.abs(position[:, :2] - start[:, :2]).max()))
        tilt = max(tilt, float(tilt_degrees(start_rotation, rotation).max()))
    elapsed = time.perf_counter() - began
    sink = float(start[-1, 2] - position[-1, 2])
    env.close()
    return {"drift_mm": 1e3 * drift, "tilt_deg": tilt, "sink_mm": 1e3 * sink, "steps_per_s": steps / elapsed,
            "physics_hz": info["physics"]["physics_hz"], "iterations": info["physics"]["solver_iterations"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0, help="simulated seconds each stack is held")
    parser.add_argument("--auto-only", action="store_true", help="only the fixed-against-auto table")
    args = parser.parse_args()
    if not args.auto_only:
        settings_tables(args.seconds)
    print(table_header("scene", "physics", "runs at", "max drift (mm)", "max tilt (deg)", "steps/s"))
    for label, n, masses in AUTO_SCENES:
        for physics in ("fixed", "auto"):
            r = hold(n, 120.0, 10, args.seconds, masses, physics)
            print(f"| {label} | {physics} | {r['physics_hz']:.0f} Hz, {r['iterations']} it. | {r['drift_mm']:.2f} | "
                  f"{r['tilt_deg']:.2f} | {r['steps_per_s']:.0f} |", flush=True)


def settings_tables(seconds: float) -> None:
    """The stacks and the mass ratios at each of :data:`SETTINGS`."""
    print(table_header("boxes", "physics Hz", "iterations", "max drift (mm)", "max tilt (deg)", "top sank (mm)",
                       "steps/s"))
    for n in (5, 10):
        for physics_hz, iterations in SETTINGS:
            r = hold(n, physics_hz, iterations, seconds)
            print(f"| {n} | {physics_hz:.0f} | {iterations} | {r['drift_mm']:.2f} | {r['tilt_deg']:.2f} | "
                  f"{r['sink_mm']:.2f} | {r['steps_per_s']:.0f} |", flush=True)
    print()
    print(table_header("bottom kg", "top kg", "physics Hz", "iterations", "max drift (mm)", "top sank (mm)"))
    for masses in RATIOS:
        for physics_hz, iterations in SETTINGS:
            r = hold(2, physics_hz, iterations, min(seconds, 10.0), masses)
            print(f"| {masses[0]:g} | {masses[1]:g} | {physics_hz:.0f} | {iterations} | {r['drift_mm']:.2f} | "
                  f"{r['sink_mm']:.2f} |", flush=True)
    print()


if __name__ == "__main__":
    main()
