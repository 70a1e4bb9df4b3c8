"""Sensors at the edge of their range: the camera's far plane against the arena wall, the IMU through an impact."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.stepping import FULL_AHEAD, STILL, nav_scene, timed_steps
from clutter_gym.sensors import SEGMENTATION_CLASSES

#: the arena wall's inner face seen from the camera at the origin (metres): the wall at 3 m less the camera
#: joint's x in base_link (diffbot.urdf)
WALL_DEPTH = 3.0 - 0.165
OBSTACLE = SEGMENTATION_CLASSES.index("obstacle")


def wall_camera(make, far: float) -> tuple[gym.Env, dict]:
    """ClutterNav-v1 with an 84x64 depth and segmentation camera (far plane ``far`` metres) at the origin facing
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
    env, first = wall_camera(lambda **kwargs: gym.make("ClutterNav-v1", **kwargs), far)
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
    and unlimited); ``make(**kwargs)`` makes the ClutterNav-v1 env."""
    noise = "none" if accel_range is None else {"profile": "none", "imu": {"accel_range": accel_range}}
    env = make(sensors=("imu",), noise=noise, terminate_on_collision=False)
    env.reset(options={"scene": nav_scene(start=(2.5, 0.0, 0.0))})
    steps, rate = timed_steps(env, FULL_AHEAD, 40)
    return np.array([obs["imu"] for obs, *_ in steps]), sum(info["n_contacts"] > 0 for *_, info in steps), rate
