"""Speed against error of the depth camera's renderer: the ray caster against TinyRenderer on ClutterFly-v1.

The scripted position controller (``CascadedFlyer`` on the subgoal) flies ClutterFly-v1 through seeded layouts;
at every pose both renderers draw the drone camera's 84x84 depth frame (interleaved, so machine noise hits them
alike). The reference is the ray cast cast through TinyRenderer's own sample points (its principal point is half a
pixel off the ideal one), so the two images sample the same rays: the ray caster meets the exact boxes and
cylinders (tests/sensors/test_ray_cast_camera.py holds it to closed forms within 1e-12 m), and the error of a
renderer is its mean and largest |depth - reference| over the pixels either sees. TinyRenderer's comes from its
polygon cylinders, its float32 depth buffer and its edge rules.

    python -m benchmarks.fidelity.camera_renderer [--steps 200]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import table_header
from clutter_gym.sensors.camera import Camera, CameraConfig
from clutter_gym.training.baselines import CascadedFlyer

SIZE = 84
RENDERERS = ("rays", "tiny")
DEFAULT = "rays"  # ClutterFly-v1's renderer for depth


def flight_states(steps: int, seed: int):
    """(env, robot state) after each of ``steps`` steps of the scripted flyer (resetting where episodes end)."""
    env = gym.make("ClutterFly-v1", sensors=("camera",), camera_renderer="tiny", subgoal_lookahead=0.5)
    obs, _ = env.reset(seed=seed)
    flyer = CascadedFlyer.for_env(env, "subgoal")
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(flyer(obs))
        if terminated or truncated:
            obs, _ = env.reset()
        yield env, env.unwrapped.robot.state()
    env.close()


def rows(steps: int = 200, seed: int = 0) -> list[dict]:
    """Per renderer: frame time (us), mean and largest |depth - reference| (mm), default flag."""
    seconds = dict.fromkeys(RENDERERS, 0.0)
    errors: dict[str, list[np.ndarray]] = {r: [] for r in RENDERERS}
    cameras: dict[str, Camera] = {}
    for env, state in flight_states(steps, seed):
        u = env.unwrapped
        if not cameras:
            link = u.sensors[0].config.link
            cameras = {r: Camera(CameraConfig(width=SIZE, height=SIZE, modes=("depth",), renderer=r, link=link))
                       for r in RENDERERS}
            reference = Camera(CameraConfig(width=SIZE, height=SIZE, modes=("depth",), renderer="rays", link=link))
            reference.intrinsics = cameras["tiny"].intrinsics  # cast through TinyRenderer's sample points
        depths = {}
        for r in RENDERERS:
            t0 = time.process_time()
            depths[r] = cameras[r].render(u.sim, state)["depth"]
            seconds[r] += time.process_time() - t0
        exact_at_tiny = reference.render(u.sim, state)["depth"]
        exact = {"rays": depths["rays"], "tiny": exact_at_tiny}
        for r in RENDERERS:
            seen = (depths[r] > 0) | (exact[r] > 0)
            errors[r].append(np.abs(depths[r] - exact[r])[seen])
    out = []
    for r in RENDERERS:
        e = np.concatenate(errors[r])
        out.append({"renderer": r, "frame_us": 1e6 * seconds[r] / steps, "mean_mm": 1e3 * float(e.mean()),
                    "max_mm": 1e3 * float(e.max()), "p99_mm": 1e3 * float(np.percentile(e, 99)),
                    "default": r == DEFAULT})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"{args.steps} scripted-flight poses in ClutterFly-v1, {SIZE}x{SIZE} depth; error against the exact ray "
          f"cast through the same sample points\n")
    print(table_header("renderer", "frame (us of CPU)", "mean error (mm)", "99th percentile (mm)", "largest (mm)"))
    for r in rows(args.steps, args.seed):
        print(f"| {r['renderer']}{' (default)' if r['default'] else ''} | {r['frame_us']:.0f} | {r['mean_mm']:.3f} | "
              f"{r['p99_mm']:.3f} | {r['max_mm']:.1f} |")


if __name__ == "__main__":
    main()
