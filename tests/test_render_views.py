"""rgb_array frames of every env show the robot and its goal at a readable size, marked, and rendering changes no
trajectory. Robot pixels are counted in pybullet's segmentation of the frame's own camera (``render_view``)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import ring_pixels

from clutter_gym import ENV_IDS
from clutter_gym.cli import DEMOS
from clutter_gym.util.camera_view import orbit_angles
from clutter_gym.util.overlay import GOAL_COLOUR, ROBOT_COLOUR

#: Least robot pixels in a 320x240 frame, per env, over the frames the demo policy's episodes give at reset and
#: every 25 steps, with margin under the measured counts (docs/envs.md, "What rgb_array shows").
LEAST_ROBOT_PIXELS = {"ClutterNav-v1": 150, "ClutterReach-v1": 2000, "ClutterFly-v1": 250}
LEAST_RING_PIXELS = 80  # a ring of the least radius is about 2 pi 8 px by 2 px


def _demo_frames(make_env, env_id: str, seeds=range(4), every: int = 25, steps: int = 75):
    """(env, frame) at reset and every ``every`` steps of the demo's scripted policy, until the episode ends."""
    kwargs, make_policy = DEMOS[env_id].kwargs, DEMOS[env_id].make_policy
    env = make_env(env_id, render_mode="rgb_array", **kwargs)
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        policy = make_policy(env)
        for t in range(steps + 1):
            if t % every == 0:
                yield env, env.render()
            obs, _, terminated, truncated, _ = env.step(policy(obs))
            if terminated or truncated:
                break


def _robot_pixels(env) -> int:
    base = env.unwrapped
    view = base.render_view()
    seg = base.sim.rendering.render_segmentation(view.width, view.height, view.eye, view.target, view.fov_deg)
    return int((seg == base.robot.body).sum())


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_frames_show_the_robot_readably_and_ring_it_and_its_goal(env_id, make_env):
    robot, robot_ring, goal_ring = [], [], []
    for env, frame in _demo_frames(make_env, env_id):
        assert frame.shape == (240, 320, 3) and frame.dtype == np.uint8
        robot.append(_robot_pixels(env))
        robot_ring.append(int(ring_pixels(frame, ROBOT_COLOUR).sum()))
        goal_ring.append(int(ring_pixels(frame, GOAL_COLOUR).sum()))
    assert min(robot) >= LEAST_ROBOT_PIXELS[env_id], robot
    assert min(robot_ring) >= LEAST_RING_PIXELS, robot_ring
    assert min(goal_ring) >= LEAST_RING_PIXELS, goal_ring


def test_the_fly_chase_camera_keeps_clutter_out_from_between_it_and_the_drone(make_env):
    for env, _ in _demo_frames(make_env, "ClutterFly-v1", seeds=range(3), every=10, steps=150):
        base = env.unwrapped
        view = base.render_view()
        drone = base.robot.state().position
        assert base.sim.rays.ray_hit_fractions([drone.tolist()], [list(view.eye)])[0] == 1.0
        assert 0.2 - 1e-6 <= np.linalg.norm(np.subtract(view.eye, drone)) <= 0.66


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_rendering_changes_no_trajectory_and_draws_nothing_from_np_random(env_id, make_env):
    rendered, plain = make_env(env_id, render_mode="rgb_array"), make_env(env_id)
    for env in (rendered, plain):
        env.reset(seed=4)
    rng = np.random.default_rng(0)
    for _ in range(40):
        action = rng.uniform(-1, 1, size=plain.action_space.shape)
        rendered.render()
        a, b = rendered.step(action), plain.step(action)
        for key in b[0]:
            np.testing.assert_array_equal(a[0][key], b[0][key])
        assert a[1:4] == b[1:4]
        if b[2] or b[3]:
            break
    assert rendered.unwrapped.np_random.bit_generator.state == plain.unwrapped.np_random.bit_generator.state


def test_the_trail_is_kept_while_rendering_and_starts_again_each_episode(make_env):
    rendered, plain = make_env(render_mode="rgb_array"), make_env()
    assert rendered.unwrapped.render().shape == (240, 320, 3)  # before the first reset too
    for env in (rendered, plain):
        env.reset(seed=0)
        for _ in range(5):
            env.step(np.array([1.0, 0.0]))
    assert len(rendered.unwrapped.render_trail.trail) == 6 and len(plain.unwrapped.render_trail.trail) == 0
    rendered.reset(seed=1)
    assert len(rendered.unwrapped.render_trail.trail) == 1


def test_human_mode_points_the_gui_camera_as_the_rgb_array_view(make_env, monkeypatch):
    """The GUI itself needs a display (test_render.py); here the call that points it is recorded."""
    env = make_env("ClutterFly-v1", render_mode="rgb_array")
    env.reset(seed=0)
    base = env.unwrapped
    calls = []
    monkeypatch.setattr(base.sim.rendering, "follow_camera", lambda *args: calls.append(args))
    monkeypatch.setattr(base, "render_mode", "human")
    assert base.render() is None
    view = base.render_view()
    (target, distance, yaw, pitch), = calls
    np.testing.assert_allclose(target, view.target)
    np.testing.assert_allclose((distance, yaw, pitch), orbit_angles(view.eye, view.target))
