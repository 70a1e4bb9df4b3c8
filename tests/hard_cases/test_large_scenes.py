"""Thousands of obstacles: placed exactly, torn down without parking what is deleted, and measured exactly."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import clutter_gym.collision.nearest
from benchmarks.hard_cases.scenes.large_scenes import grid_scene
from clutter_gym.sim import pb
from clutter_gym.worlds.pool import PARK_DEPTH


@pytest.fixture(scope="module")
def env():
    env = gym.make("ClutterNav-v1", arena_size=30.0)
    env.unwrapped.arena.near_field = False  # every obstacle a body, as in an env that renders (test_near_field.py)
    yield env
    env.close()


def test_a_large_layout_is_placed_exactly_and_torn_down_to_the_cap(env):
    big = grid_scene(2000)
    env.reset(seed=0, options={"scene": big})
    unwrapped = env.unwrapped
    cid = unwrapped.sim.client_id
    for o, body in zip(big["obstacles"], unwrapped.arena._pool.placed.items()):
        position, quaternion = pb.getBasePositionAndOrientation(body[1], physicsClientId=cid)
        np.testing.assert_allclose(position[:2], o["position"], atol=1e-9)
        yaw = o.get("yaw", 0.0)
        assert pb.getEulerFromQuaternion(quaternion)[2] == pytest.approx(np.arctan2(np.sin(yaw), np.cos(yaw)))
    env.reset(options={"scene": grid_scene(10)})
    pool = unwrapped.arena._pool
    assert pool.size == len(unwrapped.scene.obstacles) + pool.max_parked
    parked = [pb.getBasePositionAndOrientation(b, physicsClientId=cid)[0] for b in pool._parked]
    assert all(p[2] == PARK_DEPTH for p in parked)
    assert len({p[:2] for p in parked}) == len(parked)  # spread out: moving one into a pile costs per pile size


def test_nearest_obstacles_are_found_exactly_without_sorting_every_bound(env, monkeypatch):
    """The partial ordering of a large scene's candidates gives what a full sort gives, on 100 random poses."""
    env.reset(seed=0, options={"scene": grid_scene(2000)})
    unwrapped, rng = env.unwrapped, np.random.default_rng(1)
    checker = unwrapped.checker
    for _ in range(100):
        x, y = rng.uniform(-14.0, 14.0, 2)
        unwrapped.robot.reset_pose(float(x), float(y), float(rng.uniform(-np.pi, np.pi)))
        checker.sync(unwrapped.robot.state())
        partial = checker.clearance()
        with monkeypatch.context() as m:
            m.setattr(clutter_gym.collision.nearest, "SMALL_SCENE", 10**9)  # every bound sorted
            full = checker.clearance()
        for a, b in zip(partial, full):
            np.testing.assert_array_equal(a, b)


def test_a_large_scene_is_searched_near_the_robot_and_reports_what_every_obstacle_gives(env, monkeypatch):
    """ClutterNav's clearance range is the whole arena, and its checker searches near the robot first: on driven
    steps (from the cleared start corner, where the first search finds nothing) and on 100 random poses, every
    report and every shape's clearance, obstacle and witness points are what every obstacle bounded gives."""
    env.reset(seed=0, options={"scene": grid_scene(2000)})
    unwrapped, rng = env.unwrapped, np.random.default_rng(3)
    checker, check = unwrapped.checker, unwrapped.checker.check
    seen = {"in range": 0, "contacts": 0}

    def compared(state, pybullet_contacts=()):
        before = checker.audit.previous, checker._touching
        with monkeypatch.context() as m:
            m.setattr(clutter_gym.collision.nearest, "SMALL_SCENE", 10**9)  # every obstacle bounded
            expected, every = check(state, pybullet_contacts), checker.clearance()
        checker.audit.previous, checker._touching = before
        got = check(state, pybullet_contacts)
        for a, b in zip(checker.clearance(), every):
            np.testing.assert_array_equal(a, b)
        assert (got.min_clearance, got.closest, got.self_collision, got.tunneling) == (
            expected.min_clearance, expected.closest, expected.self_collision, expected.tunneling)
        for a, b in ((got.witness, expected.witness), (got.link_clearance, expected.link_clearance),
                     (got.directions, expected.directions)):
            np.testing.assert_array_equal(a, b)
        assert [(c.link, c.obstacle, c.depth, *c.position) for c in got.contacts] == [
            (c.link, c.obstacle, c.depth, *c.position) for c in expected.contacts]
        seen["in range"] += got.closest is not None
        seen["contacts"] += got.in_contact
        return got

    checker.check = compared
    try:
        env.reset(seed=0, options={"scene": grid_scene(2000)})
        for action in rng.uniform(-1.0, 1.0, (150, 2)).astype(np.float32):
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset(seed=0, options={"scene": grid_scene(2000)})
        for _ in range(100):
            x, y = rng.uniform(-14.0, 14.0, 2)
            unwrapped.robot.reset_pose(float(x), float(y), float(rng.uniform(-np.pi, np.pi)))
            checker.audit.previous = None  # a teleport: nothing to sweep
            checker.check(unwrapped.robot.state())
    finally:
        del checker.check
    assert seen["in range"] > 200 and seen["contacts"] > 5, seen
