"""What ``physics="auto"`` costs at reset: reading the columns and mass ratios of thousands of movable bodies.

``clutter_gym.auto_physics.loads`` runs at every reset of ClutterNav-v1 and ClutterReach-v1. Timed here on two
layouts of N movable bodies in the largest arena: ``floor``, the large-scene benchmark's grid of small boxes and
cylinders (``benchmarks.hard_cases.scenes.large_scenes.grid_scene``) with every obstacle given 2 kg, none on
another, and
``columns``, the same grid of 0.3 x 0.3 x 0.2 m boxes in columns of five. Figures are medians over rounds; with
``--commit`` the commit's ``loads`` (its package copied as ``benchmarks.speed.versus_commit`` copies it) alternates
with this tree's on the same scenes, and the two must give the same answers on those scenes, on the stacking
benchmark's scenes and on generated scenes whose every obstacle is movable. ``--reset`` also times a ClutterNav
reset onto each ``floor`` scene (this tree only; the first reset onto a scene builds its bodies).

    python -m benchmarks.hard_cases.auto_physics_cost                        # N = 1,000, 4,000 and 5,000
    python -m benchmarks.hard_cases.auto_physics_cost --commit main --rounds 1 --reset
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.hard_cases.scenes.large_scenes import ARENA, grid_scene
from benchmarks.hard_cases.scenes.movable_clutter import BOX, stack_scene
from benchmarks.harness import alternating_rounds, table_header
from benchmarks.speed.versus_commit import build_base, import_base
from clutter_gym.auto_physics import loads
from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.floor.scene import parse_scene

COLUMN = 5  # boxes per column of the ``columns`` layout


def floor_layout(n: int) -> dict:
    """The large-scene grid of ``n`` obstacles, every one movable (2 kg)."""
    scene = grid_scene(n)
    for obstacle in scene["obstacles"]:
        obstacle["mass"] = 2.0
    return scene


def columns_layout(n: int) -> dict:
    """``n`` boxes of :data:`BOX` (2 kg) in columns of :data:`COLUMN` on a jittered grid over the arena."""
    columns = grid_scene(-(-n // COLUMN))["obstacles"]
    boxes = [{"shape": "box", "size": list(BOX), "position": column["position"], "z": BOX[2] * k, "mass": 2.0}
             for column in columns for k in range(COLUMN)][:n]
    return {"obstacles": boxes, "start": [-14.0, 0.0, 0.0], "goal": [-12.0, 0.0]}


def todays_scenes() -> list[tuple[Obstacle, ...]]:
    """The stacking benchmark's scenes and twenty generated scenes of each env with every obstacle movable."""
    scenes = [parse_scene(stack_scene(n, masses), 4.0, 0.2).obstacles
              for n, masses in ((1, ()), (2, ()), (5, ()), (10, ()), (12, ()), (2, (1e3, 1.0)), (2, (1.0, 1e3)),
                                (2, (1.0, 1e2)))]
    for env_id in ("ClutterNav-v1", "ClutterReach-v1"):
        env = gym.make(env_id, movable_obstacles=1.0)
        for seed in range(20):
            env.reset(seed=seed)
            scenes.append(env.unwrapped.scene.obstacles)
        env.close()
    return scenes


def timed(function: Callable[[Sequence[Obstacle]], tuple[int, float]], obstacles: Sequence[Obstacle]) -> float:
    began = time.perf_counter()
    function(obstacles)
    return time.perf_counter() - began


def reset_seconds(scene: dict) -> float:
    """Seconds of a ClutterNav reset onto ``scene`` (30 m arena), after a reset onto a generated layout."""
    env = gym.make("ClutterNav-v1", arena_size=ARENA, sensors=())
    env.reset(seed=0)
    began = time.perf_counter()
    env.reset(seed=0, options={"scene": scene})
    seconds = time.perf_counter() - began
    env.close()
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 4000, 5000])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--commit", default=None, help="also time this commit's loads, alternating")
    parser.add_argument("--reset", action="store_true", help="also time a ClutterNav reset onto each floor scene")
    args = parser.parse_args()
    functions = {"this tree": loads}
    with tempfile.TemporaryDirectory() as folder:
        if args.commit:
            build_base(args.commit, Path(folder))
            functions = {args.commit: import_base("auto_physics").loads, **functions}
            scenes = todays_scenes()
            differ = [k for k, scene in enumerate(scenes) if len({f(scene) for f in functions.values()}) > 1]
            print(f"{args.commit} and this tree on {len(scenes)} of today's scenes: "
                  f"{'the same answers' if not differ else f'different answers on scenes {differ}'}\n")
        print(table_header("layout", "N movable", *(f"{name} (s)" for name in functions), "columns, ratio",
                           *(("reset (s)",) if args.reset else ())))
        for layout in (floor_layout, columns_layout):
            for n in args.sizes:
                scene = layout(n)
                obstacles = parse_scene(scene, ARENA, 0.2).obstacles
                figures = alternating_rounds({name: (lambda f=f: timed(f, obstacles)) for name, f in functions.items()},
                                             args.rounds)
                tallest, ratio = loads(obstacles)
                cells = [f"{np.median(figures[name]):.3f}" for name in functions] + [f"{tallest}, {ratio:g}"]
                if args.reset:
                    cells.append(f"{reset_seconds(scene):.2f}" if layout is floor_layout else "-")
                print(f"| {layout.__name__.removesuffix('_layout')} | {len(obstacles):,} | {' | '.join(cells)} |",
                      flush=True)


if __name__ == "__main__":
    main()
