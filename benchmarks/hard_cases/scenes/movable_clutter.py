"""Movable clutter: a box pushed into a wall, tabletop clutter at rest, and stacks of boxes."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.stepping import CONTROL_HZ, FULL_AHEAD, nav_scene, timed_steps

#: the robot drives a 1 kg box 0.5 m ahead of it into a static wall 1.2 m ahead (its near face)
PUSH_SCENE = nav_scene(start=(0.0, 0.0, 0.0), goal=(-2.0, 0.0), obstacles=[
    {"shape": "box", "size": [0.3, 0.3, 0.3], "position": [0.5, 0.0], "mass": 1.0},
    {"shape": "box", "size": [0.1, 2.0, 0.5], "position": [1.25, 0.0]},
])
PUSH_WALL_FACE, PUSH_BOX_HALF = 1.2, 0.15  # metres
BOX = (0.3, 0.3, 0.2)  # a stacked box, metres
MASS = 2.0  # a stacked box's default mass, kg


def movable_poses(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """Positions (k, 3) in metres and rotation matrices (k, 3, 3) of the env's movable bodies."""
    unwrapped = env.unwrapped
    return unwrapped.sim.obstacles.body_poses(unwrapped.movable_bodies)


def tilt_degrees(start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(k,) rotation angle between rotation matrices ``start`` and ``end`` (k, 3, 3), degrees."""
    cos = (np.einsum("kij,kij->k", start, end) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def push_box(env: gym.Env, seconds: float = 6.0) -> tuple[list[dict], np.ndarray, float]:
    """Full speed into :data:`PUSH_SCENE` for ``seconds`` (the env made with ``max_linear_speed=1.0``): each
    step's info, the box's position after each step (n, 3) in metres, and env steps/s."""
    env.reset(seed=0, options={"scene": PUSH_SCENE})
    infos, positions, elapsed = [], [], 0.0
    for _ in range(int(round(seconds * CONTROL_HZ))):
        t = time.perf_counter()
        _, reward, _, _, info = env.step(FULL_AHEAD)
        elapsed += time.perf_counter() - t
        infos.append({**info, "reward": reward})
        positions.append(movable_poses(env)[0][0].copy())
    return infos, np.array(positions), len(infos) / elapsed


def tabletop_creep(seconds: float = 10.0, seed: int = 2) -> tuple[float, float, int, float]:
    """ClutterReach-v1 with every object movable: after half a second to settle onto the table, ``seconds`` with
    the arm at rest. Returns the largest move (m) and tilt (degrees) of any object, how many obstacles stayed
    static (the shelf's), and env steps/s."""
    env = gym.make("ClutterReach-v1", movable_obstacles=1.0)
    try:
        env.reset(seed=seed)
        rest = np.zeros(7, dtype=np.float32)
        for _ in range(10):
            env.step(rest)
        settled, rotation = movable_poses(env)
        static = len(env.unwrapped.scene.obstacles) - len(settled)
        _, rate = timed_steps(env, rest, int(round(seconds * CONTROL_HZ)))
        position, later = movable_poses(env)
    finally:
        env.close()
    return float(np.abs(position - settled).max()), float(tilt_degrees(rotation, later).max()), static, rate


def stack_scene(n: int, masses: tuple[float, ...] = (), x: float = 1.5) -> dict:
    """A ClutterNav scene with ``n`` boxes of :data:`BOX` stacked exactly touching at (x, 0), the robot at the
    origin; ``masses`` bottom first (default :data:`MASS` each)."""
    masses = masses or (MASS,) * n
    boxes = [{"shape": "box", "size": list(BOX), "position": [x, 0.0], "z": BOX[2] * k, "mass": masses[k]}
             for k in range(n)]
    return {"obstacles": boxes, "start": [0.0, 0.0, 0.0], "goal": [-2.0, 0.0]}
