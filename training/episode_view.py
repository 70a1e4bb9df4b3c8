"""Top-down episode pictures for ClutterNav that explain what happened: the layout, the robot's trail, its LIDAR
beams, the planner's path (map-based envs), and a caption (step, reward terms, clearance, contact).

Several episodes play side by side (a success and a failure say more than one); a shorter episode holds its last
frame. Drawn with matplotlib from ground truth the env already has, so the pictures cost no extra rendering.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from clutter_gym.training.figures import plt
from clutter_gym.util.video import write_video

#: Side of one episode's square panel in pixels; the three caption lines sit above it.
PANEL_PX = 360
_CAPTION_PX = 75
_DPI = 100
#: The GIF shows every EVERY-th step, played at SPEEDUP times the real speed: few and small frames, so that a README
#: can embed it and drawing it takes seconds, not a minute (its size and time: docs/training.md).
EVERY = 8
SPEEDUP = 2.0


@dataclass
class EpisodeTrace:
    """What one ClutterNav episode did, step by step, for drawing."""

    title: str
    scene: Any
    arena_size: float
    robot_radius: float
    success_radius: float
    beam_angles: np.ndarray
    poses: list[tuple[float, float, float]] = field(default_factory=list)
    ranges: list[np.ndarray] = field(default_factory=list)
    captions: list[str] = field(default_factory=list)
    contacts: list[bool] = field(default_factory=list)
    path: np.ndarray | None = None


def record_episode(env: Any, policy: Callable[[Any, Any], tuple[np.ndarray, Any]], seed: int,
                   title: str) -> EpisodeTrace:
    """Roll out one episode of ``policy`` (as :meth:`Agent.predict`) in a ClutterNav env, reset with ``seed``."""
    base = env.unwrapped
    lidar = next(s for s in base.sensors if s.name == "lidar")
    obs, info = env.reset(seed=seed)
    trace = EpisodeTrace(title, base.scene, base.arena.spec.arena_size, base.robot.config.footprint_radius,
                         base.task.success_radius, np.asarray(lidar.config.angles, dtype=float))
    trace.path = base.task.planned_path(_pose(base)[:2]) if base.task.subgoal_lookahead > 0 else None
    state, total, step = None, 0.0, 0
    _append(trace, base, info, f"{title}\nstep 0", False)
    while True:
        action, state = policy(obs, state)
        obs, reward, terminated, truncated, info = env.step(action)
        total, step = total + reward, step + 1
        terms = " ".join(f"{k} {v:+.2f}" for k, v in info["reward_terms"].items() if v)
        end = " | SUCCESS" if info["is_success"] else (" | CONTACT" if info["cost"] else "")
        caption = (f"{title}\nstep {step}, return {total:.1f}, clearance {info['min_clearance'] * 100:.0f} cm{end}\n"
                   f"{terms}{_monitor_text(info)}")
        _append(trace, base, info, caption, info["cost"] > 0)
        if terminated or truncated:
            return trace


def _monitor_text(info: dict) -> str:
    """What the collision monitor did this step, when there is one and it did anything."""
    if info.get("safety_recovery"):
        return " | monitor: recovery spin"
    scale = info.get("safety_scale", 1.0)
    return f" | monitor: speed x{scale:g}" if scale < 1.0 else ""


def _pose(base: Any) -> tuple[float, float, float]:
    state = base.robot_state()
    return float(state.position[0]), float(state.position[1]), float(state.yaw)


def _append(trace: EpisodeTrace, base: Any, info: dict, caption: str, contact: bool) -> None:
    trace.poses.append(_pose(base))
    trace.ranges.append(np.asarray(info.get("lidar_ranges", np.full(len(trace.beam_angles), np.inf)), dtype=float))
    trace.captions.append(caption)
    trace.contacts.append(contact)


def draw_frame(traces: list[EpisodeTrace], t: int) -> np.ndarray:
    """(H, W, 3) uint8: every episode at its step ``t`` (or its last), side by side."""
    n = len(traces)
    height = PANEL_PX + _CAPTION_PX
    fig, axes = plt.subplots(1, n, figsize=(n * PANEL_PX / _DPI, height / _DPI), dpi=_DPI, squeeze=False)
    for ax, trace in zip(axes[0], traces):
        _draw_episode(ax, trace, min(t, len(trace.poses) - 1))
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=1.0 - (_CAPTION_PX - 4) / height, wspace=0.04)
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    plt.close(fig)
    return image


def _draw_episode(ax: Any, trace: EpisodeTrace, t: int) -> None:
    half = 0.5 * trace.arena_size
    ax.set_xlim(-half, half)
    ax.set_ylim(-half, half)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for obstacle in trace.scene.obstacles:
        ax.add_patch(_obstacle_patch(obstacle, ax))
    gx, gy = trace.scene.goal
    ax.add_patch(plt.Circle((gx, gy), trace.success_radius, color="tab:green", alpha=0.35))
    if trace.path is not None:
        ax.plot(trace.path[:, 0], trace.path[:, 1], color="tab:green", lw=1.0, ls="--", label="planner path")
    poses = np.array(trace.poses[: t + 1])
    ax.plot(poses[:, 0], poses[:, 1], color="tab:blue", lw=1.5, label="trail")
    x, y, yaw = trace.poses[t]
    ranges = trace.ranges[t]
    hit = np.isfinite(ranges)
    ends = np.where(hit, ranges, 0.0)
    angles = trace.beam_angles + yaw
    for a, r in zip(angles[hit], ends[hit]):
        ax.plot([x, x + r * math.cos(a)], [y, y + r * math.sin(a)], color="tab:red", lw=0.4, alpha=0.5)
    colour = "tab:red" if trace.contacts[t] else "tab:blue"
    ax.add_patch(plt.Circle((x, y), trace.robot_radius, color=colour, alpha=0.8))
    ax.plot([x, x + 1.4 * trace.robot_radius * math.cos(yaw)], [y, y + 1.4 * trace.robot_radius * math.sin(yaw)],
            color="white", lw=2)
    ax.set_title(trace.captions[t], fontsize=8, loc="left")


def _obstacle_patch(obstacle: Any, ax: Any) -> Any:
    from matplotlib.patches import Circle, Rectangle
    from matplotlib.transforms import Affine2D

    if obstacle.shape == "cylinder":
        return Circle(obstacle.position, 0.5 * obstacle.size[0], color="0.35")
    sx, sy = obstacle.size[0], obstacle.size[1]
    patch = Rectangle((-0.5 * sx, -0.5 * sy), sx, sy, color="0.35")
    patch.set_transform(Affine2D().rotate(obstacle.yaw).translate(*obstacle.position) + ax.transData)
    return patch


def write_episodes_video(path: str | Path, traces: list[EpisodeTrace], fps: float, every: int = EVERY,
                         speedup: float = SPEEDUP, progress: bool = False) -> Path:
    """The episodes side by side as a GIF or MP4, every ``every``-th step (and the last), played at ``speedup``
    times the real speed (``fps``: the env's steps per second); ``progress`` shows a bar of the frames drawn."""
    from tqdm import tqdm

    length = max(len(trace.poses) for trace in traces)
    steps = sorted({*range(0, length, every), length - 1})
    frames = [draw_frame(traces, t) for t in tqdm(steps, desc=f"drawing {Path(path).name}", unit="frame",
                                                  disable=not progress, dynamic_ncols=True)]
    return write_video(path, frames, fps=fps * speedup / every)
