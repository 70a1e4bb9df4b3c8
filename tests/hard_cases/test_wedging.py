"""Full command into a corner and into a gap narrower than the robot for 60 s: the simulation stays sane.

Measured: worst penetration 0.09 mm (corner) and 0.38 mm (gap), speed 0 once wedged, every value finite. The
bounds: penetration under 1 mm (a contact, not a tunnel), speed never above the commanded maximum (no energy
gained from the contacts), contacts and cost in agreement on every step.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from helpers import empty_scene

SCENES = {
    "corner": empty_scene(start=(2.0, 2.0, 0.785), goal=(-2.5, -2.5)),
    "gap": empty_scene(start=(0.0, 0.0, 0.0), goal=(-2.5, -2.5), obstacles=[
        {"shape": "box", "size": [0.4, 1.0, 0.5], "position": [1.0, 0.65]},   # a 0.3 m gap between the boxes;
        {"shape": "box", "size": [0.4, 1.0, 0.5], "position": [1.0, -0.65]},  # the robot is 0.34 m wide
    ]),
}


@pytest.mark.parametrize("name", SCENES)
def test_full_command_into_a_trap_for_a_minute(name):
    env = gym.make("ClutterNav-v0", noise="none", max_episode_steps=10_000, terminate_on_collision=False)
    env.reset(options={"scene": SCENES[name]})
    worst, fastest, touched = 0.0, 0.0, 0
    for _ in range(1200):  # 60 s at 20 Hz
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        assert all(np.all(np.isfinite(v)) for v in obs.values()) and np.isfinite(reward)
        assert (info["n_contacts"] > 0) == (info["cost"] > 0)
        worst = max(worst, info["max_penetration"])
        fastest = max(fastest, abs(float(obs["velocity"][0])))
        touched += info["n_contacts"] > 0
    x = env.unwrapped.robot.state().position[0]
    env.close()
    assert touched > 0  # it did reach the trap
    assert x < 1.0 if name == "gap" else x > 2.0  # and stayed in it
    assert worst < 1e-3
    assert fastest <= 0.5 * 1.01  # max_linear_speed
    assert abs(float(obs["velocity"][0])) < 1e-3  # wedged, not jittering
