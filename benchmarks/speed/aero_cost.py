"""What ClutterFly-v1's aerodynamic effects cost and what leaving them out costs: steps per CPU-second against the
trajectory error, for ``aero`` off, ``("drag",)``, ``("ground_effect",)`` and both (the reference).

Each setting flies the same two closed-loop flights with the scripted position controller
(:class:`~clutter_gym.training.baselines.CascadedFlyer`, aimed at the goal) in an empty volume:

* ``cruise``: 8 m at 2 m height, at most 3 m/s, where rotor drag matters;
* ``low``: 2 m close over the floor at the flyer's default 1 m/s, starting just above the lowest start a scene
  allows (the drone's bounding radius) and ending in a hover with 31 mm under the airframe, where ground effect
  matters.

Both flights run a fixed number of steps (arrival and a hover at the goal; the success radius is tiny, so no
flight ends early) and touch nothing (checked), so the error is the aerodynamics' alone: the largest and the mean
distance of the base from the reference's base at equal steps, mm. Speed: env steps per CPU-second
(``time.process_time`` around ``env.step``), the settings timed in alternating rounds in one process, median per
setting. Open loop: the vertical acceleration one control step of the hover command from rest gives, as a share of
gravity, less the same without ``aero`` (about 1e-9 g: the hover is exact to rounding), at the low flight's start
height and at the lowest start the scene generator draws; only ground effect moves it (drag needs motion).

The flyer aims at the ``goal`` entry, not at the map-based ``subgoal``: the subgoal's path keeps the drone's
bounding sphere on grid cells with room to spare (the lowest cell centre 0.3 m up at the default 0.2 m resolution),
which lifts the low flight out of ground effect, and a 0.5 m lookahead caps the default flyer at 0.75 m/s.

    python -m benchmarks.speed.aero_cost               # prints the table (about 35 CPU-seconds)
    python -m benchmarks.speed.aero_cost --rounds 2    # fewer timing rounds
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import alternating_rounds, table_header
from clutter_gym.sim import GRAVITY
from clutter_gym.training.baselines import CascadedFlyer

SETTINGS: tuple[tuple[str, ...], ...] = ((), ("drag",), ("ground_effect",), ("drag", "ground_effect"))
DEFAULT, REFERENCE = SETTINGS[0], SETTINGS[-1]
#: Base heights of the low flight, m: the start just above the drone's bounding radius (72.6 mm, the lowest start a
#: scene may give), the goal with 31 mm under the airframe (its lowest point is 13.7 mm below the base).
LOW_START_Z, LOW_GOAL_Z = 0.075, 0.045
#: Small enough that no flight is ever within it: every setting flies every step.
SUCCESS_RADIUS = 1e-6


@dataclass(frozen=True)
class Flight:
    """A closed-loop flight: an empty scene, the flyer's speed limit (m/s) and the steps flown."""

    name: str
    start: tuple[float, float, float, float]
    goal: tuple[float, float, float]
    max_speed: float
    steps: int

    def scene(self) -> dict:
        return {"obstacles": [], "start": list(self.start), "goal": list(self.goal)}


FLIGHTS = (Flight("cruise", (-4.0, 0.0, 2.0, 0.0), (4.0, 0.0, 2.0), 3.0, 150),
           Flight("low", (-1.0, 0.0, LOW_START_Z, 0.0), (1.0, 0.0, LOW_GOAL_Z), 1.0, 150))


def label(aero: tuple[str, ...]) -> str:
    return " + ".join(aero) if aero else "off"


def make_env(aero: tuple[str, ...]) -> gym.Env:
    return gym.make("ClutterFly-v1", sensors=(), aero=aero, success_radius=SUCCESS_RADIUS, max_episode_steps=10_000)


def fly(env: gym.Env, flight: Flight) -> tuple[np.ndarray, float]:
    """The base positions after each step of ``flight``, and the CPU seconds spent in ``env.step``.

    Raises:
        RuntimeError: the episode ended, or the drone touched something (the floor): the flights would not compare
            the aerodynamics alone.
    """
    obs, _ = env.reset(options={"scene": flight.scene()})
    flyer = CascadedFlyer.for_env(env, "goal", max_speed=flight.max_speed)
    robot, seconds = env.unwrapped.robot, 0.0
    path = np.empty((flight.steps, 3))
    for i in range(len(path)):
        action = flyer(obs)
        t0 = time.process_time()
        obs, _, terminated, truncated, info = env.step(action)
        seconds += time.process_time() - t0
        path[i] = robot.state().position
        if terminated or truncated or info["cost"]:
            raise RuntimeError(f"the {flight.name} flight {'touched something' if info['cost'] else 'ended'} at step "
                               f"{i} under aero={robot.config.aero}: the error would not be the aerodynamics' alone")
    return path, seconds


def hover_lift(env: gym.Env, height: float) -> float:
    """Vertical acceleration over one control step of the hover command from rest, level at ``height`` (base, m),
    as a share of gravity: the open-loop thrust change."""
    env.reset(options={"scene": {"obstacles": [], "start": [0.0, 0.0, height, 0.0], "goal": [1.0, 0.0, height]}})
    unwrapped = env.unwrapped
    env.step(unwrapped.robot.hover_action(GRAVITY).astype(np.float32))
    step_s = unwrapped.substeps / unwrapped.sim.physics_hz
    return unwrapped.robot.state().linear_velocity[2] / step_s / GRAVITY


def lowest_spawn_height(env: gym.Env) -> float:
    """The lowest base height the scene generator draws a start or goal at, m: the lowest cell centre with the
    spawn clearance beyond the drone's bounding radius to the floor."""
    task = env.unwrapped.task
    heights = task.spec.cell_centres[2]
    return float(heights[heights > task.robot_radius + task.spec.spawn_clearance].min())


def rows(rounds: int = 8) -> list[dict]:
    """Per setting (in :data:`SETTINGS` order): ``aero``, ``label``, ``rate`` (median steps per CPU-second),
    ``error_mm`` (largest distance from the reference over both flights), ``mean_mm`` (mean over both flights'
    steps), ``<flight>_mm`` (largest per flight), ``lift_low`` and ``lift_spawn`` (the hover lift the setting adds to
    that without ``aero``, a share of gravity, at the low flight's start and at :func:`lowest_spawn_height`, whose
    value is ``spawn_height``), ``default`` and ``reference``."""
    envs = {aero: make_env(aero) for aero in SETTINGS}
    paths: dict[tuple[str, ...], list[np.ndarray]] = {}

    def measure(aero: tuple[str, ...]) -> float:
        flown = [fly(envs[aero], flight) for flight in FLIGHTS]
        if aero not in paths:
            paths[aero] = [p for p, _ in flown]
        elif not all(np.array_equal(p, q) for (p, _), q in zip(flown, paths[aero])):
            raise RuntimeError(f"aero={aero} flew a different path in a later round: the timings would differ")
        return sum(f.steps for f in FLIGHTS) / sum(s for _, s in flown)

    rates = alternating_rounds({aero: (lambda aero=aero: measure(aero)) for aero in SETTINGS}, rounds)
    spawn = lowest_spawn_height(envs[DEFAULT])
    lifts = {aero: (hover_lift(envs[aero], LOW_START_Z), hover_lift(envs[aero], spawn)) for aero in SETTINGS}
    out = []
    for aero in SETTINGS:
        gaps = [1e3 * np.linalg.norm(p - r, axis=1) for p, r in zip(paths[aero], paths[REFERENCE])]
        row = {"aero": aero, "label": label(aero), "rate": statistics.median(rates[aero]),
               "error_mm": float(max(g.max() for g in gaps)), "mean_mm": float(np.concatenate(gaps).mean()),
               "lift_low": lifts[aero][0] - lifts[()][0], "lift_spawn": lifts[aero][1] - lifts[()][1],
               "spawn_height": spawn, "default": aero == DEFAULT, "reference": aero == REFERENCE}
        row.update({f"{f.name}_mm": float(g.max()) for f, g in zip(FLIGHTS, gaps)})
        out.append(row)
    for env in envs.values():
        env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=8, help="alternating timing rounds (default 8)")
    args = parser.parse_args()
    measured = rows(args.rounds)
    spawn = measured[0]["spawn_height"]
    print(f"ClutterFly-v1 without sensors; {', '.join(f'{f.name} {f.steps} steps' for f in FLIGHTS)}; median of "
          f"{args.rounds} alternating rounds; error against aero={REFERENCE}\n")
    print(table_header("aero", "steps per CPU-s", "max error (mm)", "mean error (mm)",
                       *(f"{f.name} max (mm)" for f in FLIGHTS), f"hover lift at {1e3 * LOW_START_Z:.0f} mm (% of g)",
                       f"hover lift at {spawn:.1f} m (% of g)"))
    for r in measured:
        name = r["label"] + (" (default)" if r["default"] else " (reference)" if r["reference"] else "")
        print(f"| {name} | {r['rate']:,.0f} | {r['error_mm']:.2f} | {r['mean_mm']:.2f} | "
              + " | ".join(f"{r[f'{f.name}_mm']:.2f}" for f in FLIGHTS)
              + f" | {_percent(r['lift_low'], 3)} | {_percent(r['lift_spawn'], 4)} |")


def _percent(share: float, digits: int) -> str:
    """``share`` in per cent, without a sign on a value that rounds to zero."""
    return f"{round(100 * share, digits) + 0.0:.{digits}f}"


if __name__ == "__main__":
    main()
