"""The scenes and runs of the hard cases in tests/hard_cases/ that have a figure to measure: a base standing still,
full command into a corner and into a gap, the camera's far plane, the IMU through an impact, a box pushed into a
wall, tabletop clutter at rest. The tests assert on what these return; ``benchmarks.hard_cases.catalogue`` prints short
versions of the same runs beside their steps/s.

Every run returns its figures (metres, radians, m/s, m/s^2) and the env steps/s of its timed steps.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.hard_cases.stacking import tilt_degrees
from clutter_gym.sensors import SEGMENTATION_CLASSES

CONTROL_HZ = 20.0  # ClutterNav-v0 and ClutterReach-v0 control steps per second
STILL = np.zeros(2, dtype=np.float32)
FULL_AHEAD = np.array([1.0, 0.0], dtype=np.float32)


def nav_scene(start=(0.0, 0.0, 0.0), goal=(2.5, 2.5), obstacles=()) -> dict:
    """A ClutterNav scene in the reset-options format: start (x, y, yaw), goal (x, y), obstacles as dicts."""
    return {"obstacles": list(obstacles), "start": list(start), "goal": list(goal)}


def timed_steps(env: gym.Env, action: np.ndarray, n: int) -> tuple[list[tuple], float]:
    """``n`` steps of ``action``: each step's (obs, reward, terminated, truncated, info), and env steps/s."""
    out, began = [], time.perf_counter()
    for _ in range(n):
        out.append(env.step(action))
    return out, n / (time.perf_counter() - began)


# ------------------------------------------------------------------------------------------------ standing still
def base_pose(env: gym.Env) -> tuple[np.ndarray, float]:
    """The nav robot's (x, y) in metres and heading in radians."""
    state = env.unwrapped.robot.state()
    return state.position[:2].copy(), float(np.arctan2(state.rotation[1, 0], state.rotation[0, 0]))


def standstill_drift(env: gym.Env, yaw: float, before: tuple[float, float], seconds: float = 20.0
                     ) -> tuple[float, float, float]:
    """From (-1, 0) facing ``yaw``: 2 s of command ``before``, 1 s at zero command to come to rest, then
    ``seconds`` at zero command. Returns how far the base moved (m) and turned (rad) over those seconds, and env
    steps/s while holding."""
    env.reset(seed=0, options={"scene": nav_scene(start=(-1.0, 0.0, yaw))})
    for _ in range(40):
        env.step(np.array(before, dtype=np.float32))
    for _ in range(20):
        env.step(STILL)
    xy, heading = base_pose(env)
    _, rate = timed_steps(env, STILL, int(round(seconds * CONTROL_HZ)))
    xy_after, heading_after = base_pose(env)
    return float(np.linalg.norm(xy_after - xy)), abs(heading_after - heading), rate


# ------------------------------------------------------------------------------------------------ wedging
WEDGES = {
    "corner": nav_scene(start=(2.0, 2.0, 0.785), goal=(-2.5, -2.5)),
    "gap": nav_scene(start=(0.0, 0.0, 0.0), goal=(-2.5, -2.5), obstacles=[
        {"shape": "box", "size": [0.4, 1.0, 0.5], "position": [1.0, 0.65]},   # a 0.3 m gap between the boxes;
        {"shape": "box", "size": [0.4, 1.0, 0.5], "position": [1.0, -0.65]},  # the robot is 0.34 m wide
    ]),
}


@dataclass(frozen=True)
class Wedged:
    """Full command into a trap: worst FCL penetration (m), fastest and final forward speed (m/s), steps in
    contact, steps where contacts and cost disagree, whether every observation and reward was finite, the final x
    (m), and env steps/s."""

    penetration: float
    fastest: float
    final_speed: float
    touched: int
    mismatched: int
    finite: bool
    final_x: float
    steps_per_s: float


def wedge(name: str, seconds: float = 60.0) -> Wedged:
    """Full forward command into :data:`WEDGES` ``name`` for ``seconds``."""
    env = gym.make("ClutterNav-v0", noise="none", max_episode_steps=10_000, terminate_on_collision=False)
    try:
        env.reset(options={"scene": WEDGES[name]})
        steps, rate = timed_steps(env, FULL_AHEAD, int(round(seconds * CONTROL_HZ)))
        x = float(env.unwrapped.robot.state().position[0])
    finally:
        env.close()
    infos = [info for *_, info in steps]
    speeds = [abs(float(obs["velocity"][0])) for obs, *_ in steps]
    finite = all(all(np.all(np.isfinite(v)) for v in obs.values()) and np.isfinite(r) for obs, r, *_ in steps)
    return Wedged(max(i["max_penetration"] for i in infos), max(speeds), speeds[-1],
                  sum(i["n_contacts"] > 0 for i in infos), sum((i["n_contacts"] > 0) != (i["cost"] > 0) for i in infos),
                  finite, x, rate)


# ------------------------------------------------------------------------------------------------ sensor edges
#: the arena wall's inner face seen from the camera at the origin (metres): the wall at 3 m less the camera
#: joint's x in base_link (diffbot.urdf)
WALL_DEPTH = 3.0 - 0.165
OBSTACLE = SEGMENTATION_CLASSES.index("obstacle")


def wall_camera(make, far: float) -> tuple[gym.Env, dict]:
    """ClutterNav-v0 with an 84x64 depth and segmentation camera (far plane ``far`` metres) at the origin facing
    the arena wall, reset on an empty scene: the env and its first observation. ``make(**kwargs)`` makes the
    env; the caller closes it."""
    env = make(sensors=("camera",), camera_modes=("depth", "segmentation"), camera_size=(84, 64), camera_far=far)
    obs, _ = env.reset(options={"scene": nav_scene()})
    return env, obs


def wall_view(make, far: float) -> tuple[np.ndarray, np.ndarray]:
    """The depth (m) and segmentation images of :func:`wall_camera`'s first frame."""
    _, obs = wall_camera(make, far)
    return obs["camera_depth"], obs["camera_segmentation"]


def wall_depth_error(far: float, steps: int) -> tuple[float, float, int, float]:
    """Largest |depth - :data:`WALL_DEPTH`| (m) over the wall's pixels in :func:`wall_camera`'s first frame (the
    pose the closed form is for), the same over ``steps`` more frames at zero command (the base settles by about
    10 um on its wheels, which the closed form does not follow), the wall's pixel count in the first frame, and env
    steps/s (camera on)."""
    env, first = wall_camera(lambda **kwargs: gym.make("ClutterNav-v0", **kwargs), far)
    try:
        frames, rate = timed_steps(env, STILL, steps)
    finally:
        env.close()
    errors = []
    for obs in [first] + [obs for obs, *_ in frames]:
        wall = obs["camera_segmentation"] == OBSTACLE
        errors.append(float(np.abs(obs["camera_depth"][wall] - WALL_DEPTH).max()))
    return errors[0], max(errors[1:], default=0.0), int((first["camera_segmentation"] == OBSTACLE).sum()), rate


def imu_impact(make, accel_range: float | None = None) -> tuple[np.ndarray, int, float]:
    """Full command from 0.3 m in front of the arena wall for 2 s: the IMU readings (40, 6) (m/s^2, rad/s), the
    steps in contact, and env steps/s. ``accel_range``: the accelerometer's full scale, m/s^2 (None: noiseless
    and unlimited); ``make(**kwargs)`` makes the ClutterNav-v0 env."""
    noise = "none" if accel_range is None else {"profile": "none", "imu": {"accel_range": accel_range}}
    env = make(sensors=("imu",), noise=noise, terminate_on_collision=False)
    env.reset(options={"scene": nav_scene(start=(2.5, 0.0, 0.0))})
    steps, rate = timed_steps(env, FULL_AHEAD, 40)
    return np.array([obs["imu"] for obs, *_ in steps]), sum(info["n_contacts"] > 0 for *_, info in steps), rate


# ------------------------------------------------------------------------------------------------ movable clutter
#: the robot drives a 1 kg box 0.5 m ahead of it into a static wall 1.2 m ahead (its near face)
PUSH_SCENE = nav_scene(start=(0.0, 0.0, 0.0), goal=(-2.0, 0.0), obstacles=[
    {"shape": "box", "size": [0.3, 0.3, 0.3], "position": [0.5, 0.0], "mass": 1.0},
    {"shape": "box", "size": [0.1, 2.0, 0.5], "position": [1.25, 0.0]},
])
PUSH_WALL_FACE, PUSH_BOX_HALF = 1.2, 0.15  # metres


def movable_poses(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """Positions (k, 3) in metres and rotation matrices (k, 3, 3) of the env's movable bodies."""
    unwrapped = env.unwrapped
    return unwrapped.sim.body_poses(unwrapped.movable_bodies)


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
    """ClutterReach-v0 with every object movable: after half a second to settle onto the table, ``seconds`` with
    the arm at rest. Returns the largest move (m) and tilt (degrees) of any object, how many obstacles stayed
    static (the shelf's), and env steps/s."""
    env = gym.make("ClutterReach-v0", movable_obstacles=1.0)
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
