"""Large scenes keep only the static obstacles near the robot in the physics world (worlds/near_field.py).

What must not change: every ray of the exact caster and every pixel of the ray-cast camera (the far obstacles are the
primitives' backdrop), the collision checker (it holds every obstacle), and the physics wherever the robot touches
nothing that was given a body after the reset. What must hold: every obstacle the robot could reach in a step is a
body before the step.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from benchmarks.hard_cases.scenes.large_scenes import ARENA, grid_scene
from clutter_gym.sim import Sim
from clutter_gym.sim.primitives import BACKDROP_ID
from clutter_gym.worlds.near_field import NEAR_FIELD_FROM

N = 1000  # 0.9 m apart on the 30 m grid: room to drive between them


def make(near: bool = True, **kwargs) -> gym.Env:
    env = gym.make("ClutterNav-v1", arena_size=ARENA, **kwargs)
    env.unwrapped.arena.near_field = near
    return env


def forward_actions(steps: int, seed: int = 1) -> np.ndarray:
    """Seeded random actions that mostly drive forward, into the grid."""
    actions = np.random.default_rng(seed).uniform(-1.0, 1.0, (steps, 2))
    actions[:, 0] = np.abs(actions[:, 0])
    return actions


def lane_scene() -> dict:
    """The grid with a 2 m wide lane along y = 0, which the robot drives down without touching anything."""
    scene = grid_scene(N)
    scene["obstacles"] = [o for o in scene["obstacles"] if abs(o["position"][1]) > 1.0]
    return scene


def fan(position: np.ndarray, reach: float = 14.0, n: int = 720) -> tuple[np.ndarray, np.ndarray]:
    """Rays from ``position`` at three heights in every direction, world frame."""
    angles = np.linspace(-np.pi, np.pi, n, endpoint=False)
    starts, ends = [], []
    for z, dz in ((0.1, 0.0), (0.3, 0.05), (0.45, -0.2)):
        start = np.array([position[0], position[1], z])
        direction = np.stack([np.cos(angles), np.sin(angles), np.full(n, dz)], axis=1)
        starts.append(np.broadcast_to(start, (n, 3)))
        ends.append(start + reach * direction)
    return np.ascontiguousarray(np.concatenate(starts)), np.ascontiguousarray(np.concatenate(ends))


def what_is_seen(env: gym.Env, ids: np.ndarray) -> np.ndarray:
    """Per pixel of ``Sim.ray_cast_image``'s ids: 0 nothing, 1 the ground, 2 an obstacle (its body or the backdrop)."""
    return np.select([ids == -1, ids == env.unwrapped.sim.bodies["ground"]], [0, 1], 2)


def test_a_large_scene_keeps_only_near_obstacles_as_bodies():
    env = make()
    env.reset(seed=0, options={"scene": grid_scene(N)})
    arena = env.unwrapped.arena
    assert arena.near_field_engaged
    for action in forward_actions(100):
        env.step(action)
    assert 0 < len(arena._pool.placed) < N // 10
    env.reset(seed=0, options={"scene": grid_scene(NEAR_FIELD_FROM - 1)})  # a smaller scene: every obstacle a body
    assert not arena.near_field_engaged
    assert len(arena._pool.placed) == len(env.unwrapped.scene.obstacles)
    env.close()


@pytest.mark.parametrize("kwargs", [{"render_mode": "rgb_array"}, {"lidar_caster": "pybullet"},
                                    {"sensors": ("lidar", "camera"), "camera_renderer": "tiny"}])
def test_an_env_that_reads_bodies_keeps_every_obstacle_a_body(kwargs):
    env = gym.make("ClutterNav-v1", arena_size=ARENA, **kwargs)
    scene = grid_scene(NEAR_FIELD_FROM + 10)
    env.reset(seed=0, options={"scene": scene})
    assert not env.unwrapped.arena.near_field_engaged
    assert len(env.unwrapped.arena._pool.placed) == len(env.unwrapped.scene.obstacles)
    env.close()


def test_rays_and_camera_see_the_whole_scene_exactly():
    """Along a drive through the grid, the exact caster's rays and the ray-cast camera's depth from the robot are bit
    for bit those of the same scene with every obstacle a body, and every obstacle pixel is an obstacle's (a body's,
    or the backdrop's)."""
    near, full = make(True), make(False)
    scene = grid_scene(N)
    near.reset(seed=0, options={"scene": scene})
    full.reset(seed=0, options={"scene": scene})
    refreshes = backdrop_pixels = 0
    for k, action in enumerate(forward_actions(240)):
        near.step(action)
        if k % 8:
            continue
        state = near.unwrapped.robot.state()
        starts, ends = fan(state.position)
        np.testing.assert_array_equal(near.unwrapped.sim.rays.cast_exact(starts, ends),
                                      full.unwrapped.sim.rays.cast_exact(starts, ends))
        # the camera's view from the robot, drawn in both worlds (the full world's robot is elsewhere: not drawn)
        eye = np.array([state.position[0], state.position[1], 0.3])
        forward, left = state.rotation[:, 0], state.rotation[:, 1]
        axes = np.array([forward, -left, [0.0, 0.0, -1.0]])
        intrinsics = (60.0, 60.0, 47.5, 35.5)
        depth, ids = near.unwrapped.sim.rendering.ray_cast_image(96, 72, eye, axes, intrinsics, 0.05, 12.0)
        depth_full, ids_full = full.unwrapped.sim.rendering.ray_cast_image(96, 72, eye, axes, intrinsics, 0.05, 12.0)
        np.testing.assert_array_equal(depth, depth_full)
        np.testing.assert_array_equal(what_is_seen(near, ids), what_is_seen(full, ids_full))
        backdrop_pixels += int((ids == BACKDROP_ID).sum())
        refreshes = near.unwrapped.arena._near.refreshes
    assert refreshes > 3 and backdrop_pixels > 0  # the bodies changed along the way, and far obstacles were seen
    near.close()
    full.close()


def test_every_obstacle_the_robot_can_reach_in_a_step_is_a_body():
    env = make()
    scene = grid_scene(N)
    env.reset(seed=0, options={"scene": scene})
    u = env.unwrapped
    obstacles = u.scene.obstacles
    centres = np.array([o.centre for o in obstacles])
    enclosing = 0.5 * np.linalg.norm([o.size for o in obstacles], axis=1)
    touched = disagreements = 0
    for action in forward_actions(300, seed=2):
        _, _, terminated, truncated, info = env.step(action)
        centre, reach = u.checker.model.bounding_ball()
        near = np.flatnonzero(np.linalg.norm(centres - centre, axis=1) - enclosing <= reach + 0.05)
        assert set(near.tolist()) <= set(u.arena._pool.placed)
        touched += info["n_contacts"] > 0
        disagreements += info["contact_disagreement"]
        if terminated or truncated:
            env.reset(seed=0, options={"scene": scene})
    # pybullet's contacts are counted against the bodies given since the reset: were they not, every step touching
    # one would disagree with FCL (the full world disagrees on 1 of these 178 steps, at the tolerance)
    assert touched > 100
    assert disagreements <= 2
    env.close()


def test_a_drive_that_touches_nothing_is_the_full_worlds_bit_for_bit():
    """Down a clear lane, across many refreshes, the trajectory and every observation are the full world's. (Touching
    an obstacle given a body after the reset may differ in the last bits: its contact pair is ordered after the
    robot, not before.)"""
    runs = []
    camera = {"sensors": ("lidar", "camera"), "camera_renderer": "rays", "camera_modes": ("depth", "segmentation")}
    for near in (True, False):
        env = make(near, **camera)
        env.reset(seed=0, options={"scene": {**lane_scene(), "start": [-14.0, 0.0, 0.0], "goal": [14.0, 0.0]}})
        states = []
        for _ in range(250):
            obs, reward, *_ = env.step(np.array([1.0, 0.0]))
            states.append((env.unwrapped.robot.state().position.copy(), obs, reward))
        runs.append((states, env.unwrapped.arena._near.refreshes))
        env.close()
    (near_states, refreshes), (full_states, _) = runs
    assert refreshes > 5
    for (p, obs, r), (q, obs_full, r_full) in zip(near_states, full_states):
        np.testing.assert_array_equal(p, q)
        for key in obs:  # the LIDAR, and the camera's depth and classes (far obstacles drawn from the backdrop)
            np.testing.assert_array_equal(obs[key], obs_full[key])
        assert r == r_full


def test_the_same_seed_gives_the_same_trajectory():
    def run() -> list:
        env = make()
        env.reset(seed=3, options={"scene": grid_scene(N)})
        out = [env.step(a)[0]["lidar"] for a in forward_actions(150, seed=3)]
        env.close()
        return out

    for a, b in zip(run(), run()):
        np.testing.assert_array_equal(a, b)


def test_the_backdrop_is_seen_only_where_it_is_shown():
    sim = Sim(visuals=False)
    sim.add_ground(visual_size=10.0)
    rotations = np.repeat(np.eye(3)[None], 2, axis=0)
    sim.primitives.set_backdrop(["box", "cylinder"], np.array([[2.0, 0.0, 0.5], [-2.0, 0.0, 0.5]]), rotations,
                                np.array([[0.5, 0.5, 0.5], [0.25, 0.25, 0.5]]))
    starts = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.5]])
    ends = np.array([[10.0, 0.0, 0.5], [-10.0, 0.0, 0.5]])
    np.testing.assert_array_equal(sim.rays.cast_exact(starts, ends), [1.0, 1.0])  # none shown yet
    sim.primitives.show_backdrop(np.array([True, False]))
    np.testing.assert_allclose(sim.rays.cast_exact(starts, ends), [0.15, 1.0])
    sim.primitives.show_backdrop(np.array([True, True]))
    np.testing.assert_allclose(sim.rays.cast_exact(starts, ends), [0.15, 0.175])
    ids = sim.primitives.arrays()[0]
    assert (ids == BACKDROP_ID).sum() == 2
    with pytest.raises(ValueError, match="one flag per backdrop row"):
        sim.primitives.show_backdrop(np.array([True]))
    with pytest.raises(RuntimeError, match="near_field = False"):  # pybullet's rays would pass through them
        sim.rays.ray_hit_fractions(starts, ends, caster="pybullet")
    sim.primitives.clear_backdrop()
    np.testing.assert_array_equal(sim.rays.cast_exact(starts, ends), [1.0, 1.0])
    sim.close()
