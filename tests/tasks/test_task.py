"""Reward terms, success and weights of the navigation task."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import empty_scene


def test_goal_within_reach_is_a_success(make_env):
    env = make_env(success_weight=7.0)
    env.reset(options={"scene": empty_scene(goal=(0.2, 0.0))})
    _, reward, terminated, truncated, info = env.step(np.zeros(2))
    assert terminated and not truncated and info["is_success"]
    assert info["reward_terms"]["success"] == 7.0


def test_goal_observation_is_distance_and_bearing_in_the_robot_frame(make_env):
    env = make_env()
    obs, _ = env.reset(options={"scene": empty_scene(start=(0.0, 0.0, np.pi / 2), goal=(2.0, 0.0))})
    distance, sin_b, cos_b = obs["goal"]
    assert distance == pytest.approx(2.0, abs=1e-6)
    # the goal lies along world +x; the robot faces +y, so the goal is 90 degrees to its right
    assert sin_b == pytest.approx(-1.0, abs=1e-6) and cos_b == pytest.approx(0.0, abs=1e-6)


def test_terms_at_a_known_clearance(make_env):
    """The robot starts 0.05 m from a wall: clearance term = -w * (0.1 - 0.05) / 0.1 = -0.25 for w = 0.5."""
    box = {"shape": "box", "size": [0.2, 2.0, 0.5], "position": [0.32, 0.0], "yaw": 0.0}
    env = make_env(clearance_weight=0.5, clearance_margin=0.1, control_weight=0.01, time_weight=0.01)
    env.reset(options={"scene": empty_scene(obstacles=[box])})
    _, reward, _, _, info = env.step(np.array([0.0, 0.0]))
    terms = info["reward_terms"]
    assert info["min_clearance"] == pytest.approx(0.05, abs=2e-3)
    assert terms["clearance"] == pytest.approx(-0.25, abs=0.01)
    assert terms["time"] == -0.01 and terms["control"] == 0.0 and terms["contact"] == 0.0
    assert reward == pytest.approx(sum(terms.values()))


def test_progress_and_control_terms(make_env):
    env = make_env(progress_weight=10.0, control_weight=0.02)
    env.reset(options={"scene": empty_scene(goal=(2.5, 0.0))})
    before = env.unwrapped.robot.state().position[0]
    _, _, _, _, info = env.step(np.array([1.0, 0.5]))
    after = env.unwrapped.robot.state().position
    progress = 2.5 - before - np.hypot(2.5 - after[0], after[1])
    assert info["reward_terms"]["progress"] == pytest.approx(10.0 * progress, rel=1e-6)
    assert info["reward_terms"]["control"] == pytest.approx(-0.02 * 1.25)


def test_weights_scale_their_terms(make_env):
    a, b = make_env(contact_weight=1.0), make_env(contact_weight=3.0)
    box = {"shape": "box", "size": [0.2, 2.0, 0.5], "position": [0.3, 0.0], "yaw": 0.0}
    for env in (a, b):
        env.reset(options={"scene": empty_scene(start=(0.0, 0.0, 0.0), obstacles=[box])})
    for _ in range(15):
        info_a = a.step(np.array([1.0, 0.0]))[4]
        info_b = b.step(np.array([1.0, 0.0]))[4]
    assert info_a["n_contacts"] > 0
    assert info_b["reward_terms"]["contact"] == 3 * info_a["reward_terms"]["contact"]


def test_the_reverse_term_charges_backward_speed_only_when_asked():
    import gymnasium as gym

    scene = {"obstacles": [], "start": [0.0, 0.0, 0.3], "goal": [2.5, 2.5]}
    for weight, command in ((0.5, -1.0), (0.5, 1.0), (0.0, -1.0)):
        env = gym.make("ClutterNav-v1", reverse_weight=weight)
        obs, _ = env.reset(seed=0, options={"scene": scene})
        for _ in range(20):
            obs, _, _, _, info = env.step(np.array([command, 0.0], dtype=np.float32))
        env.close()
        speed = float(obs["velocity"][0])  # forward speed, m/s (clean sensors: exact)
        if weight == 0.0:
            assert "reverse" not in info["reward_terms"]  # the default reward is unchanged
        elif command < 0:
            assert speed < -0.3 and info["reward_terms"]["reverse"] == pytest.approx(weight * speed, abs=0.02)
        else:
            assert info["reward_terms"]["reverse"] == 0.0


def test_forward_only_driving_maps_the_linear_action_onto_stand_to_full_speed(make_env):
    """reverse=False: -1 stands, 0 drives at half speed, 1 at full speed; the control charge is on that command."""
    for action, speed in ((-1.0, 0.0), (0.0, 0.25), (1.0, 0.5)):
        env = make_env(reverse=False)
        env.reset(seed=0, options={"scene": empty_scene()})
        for _ in range(20):
            obs, _, _, _, info = env.step(np.array([action, 0.0], dtype=np.float32))
        assert float(obs["velocity"][0]) == pytest.approx(speed, abs=0.01)
        assert info["reward_terms"]["control"] == pytest.approx(-0.01 * ((action + 1.0) / 2.0) ** 2)
    with pytest.raises(ValueError, match="reverse must be True or False"):
        make_env(reverse="no")


def test_the_monitor_holds_the_forward_only_command_it_drives(make_env):
    """A wall ahead at full speed: the monitor stops the base whether the action is 1 (full) or 0 (half speed)."""
    wall = {"shape": "box", "size": [0.1, 2.0, 0.5], "position": [0.6, 0.0], "yaw": 0.0}
    for action in (1.0, 0.0):
        env = make_env(reverse=False, sensors=["lidar"], safety_horizon=0.5)
        env.reset(seed=0, options={"scene": empty_scene(goal=(-2.5, 2.5), obstacles=[wall])})
        for _ in range(60):
            _, _, _, _, info = env.step(np.array([action, 0.0], dtype=np.float32))
        assert info["cost"] == 0.0 and info["safety_scale"] == 0.0 and info["min_clearance"] > 0.0


def test_the_bearing_entry_is_the_goal_angle_and_jumps_straight_behind(make_env):
    """observe_bearing: goal = (distance, sin, cos, bearing / pi); just left of straight behind it reads near 1, just
    right near -1, where sin and cos hardly differ."""
    env = make_env(observe_bearing=True, sensors=["lidar"])
    assert env.observation_space["goal"].shape == (4,)
    readings = []
    for goal_y in (0.05, -0.05):  # the goal 2.5 m behind the robot, a little to its left, then to its right
        obs, _ = env.reset(options={"scene": empty_scene(start=(0.0, 0.0, 0.0), goal=(-2.5, goal_y))})
        distance, sin_b, cos_b, angle = obs["goal"]
        assert angle == pytest.approx(np.arctan2(goal_y, -2.5) / np.pi, abs=1e-6)
        assert distance == pytest.approx(np.hypot(2.5, goal_y), abs=1e-3) and cos_b < -0.99
        readings.append(angle)
    assert readings[0] > 0.99 and readings[1] < -0.99
    assert make_env(sensors=["lidar"]).observation_space["goal"].shape == (3,)  # the default is unchanged
