"""Wedging: full command into a corner and into a gap narrower than the robot."""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from benchmarks.hard_cases.scenes.stepping import CONTROL_HZ, FULL_AHEAD, nav_scene, timed_steps

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
    env = gym.make("ClutterNav-v1", noise="none", max_episode_steps=10_000, terminate_on_collision=False)
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
