"""The joint-space planner reference for ClutterReach: IK against the simulator's forward kinematics, the
clearance margin, collision-free paths checked finer than they were planned, and clean reaches in the env."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.training.joint_planner import (
    GOAL_BALL,
    ConfigurationChecker,
    JointPlannerReacher,
    _time_parameterise,
    inverse_kinematics,
)
from clutter_gym.worlds.scene import Obstacle

READY = np.array([0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4])
SHELF_SEED = 1_000_000  # the first evaluation layout: its target is inside the shelf, no straight line reaches it


@pytest.fixture(scope="module")
def checker():
    return ConfigurationChecker()


def test_ik_solutions_put_the_simulated_end_effector_on_the_target(checker, make_env):
    target = np.array([0.45, -0.2, 0.25])
    seeds = np.random.default_rng(0).uniform(-1.0, 1.0, (16, 7)) + READY
    solutions = inverse_kinematics(checker, target, seeds)
    assert len(solutions) >= 4
    env = make_env("ClutterReach-v0")
    for q in solutions[:4]:  # pybullet's own kinematics agree with the numpy FK the planner uses
        obs, _ = env.reset(seed=0, options={"scene": {"obstacles": [], "start": q.tolist(), "target": [0.3, 0, 0.5]}})
        assert np.linalg.norm(obs["ee_position"] - target) < 0.006


def test_margin_is_the_least_distance_to_the_layout():
    box = Obstacle("box", (0.1, 0.1, 0.3), (0.55, 0.0), 0.0)
    far = ConfigurationChecker(margin=1.0)
    far.set_obstacles([box])
    clearance = far.clearance(READY)
    assert 0.02 < clearance < 0.5
    for margin, free in ((clearance - 0.005, True), (clearance + 0.005, False)):
        c = ConfigurationChecker(margin=margin)
        c.set_obstacles([box])
        assert c.free(READY[None])[0] == free


def test_a_blocked_batch_stops_at_its_first_blocked_configuration(checker):
    checker.set_obstacles([Obstacle("box", (0.2, 0.2, 0.6), (0.3, 0.0), 0.0)])  # through the ready hand
    assert not checker.free(np.stack([READY, READY + 0.05])).any()
    checker.set_obstacles([])
    assert checker.free(np.stack([READY, READY + 0.05]), stop_at_first=False).all()


def test_shelf_path_is_collision_free_at_five_times_the_planning_resolution(make_env):
    env = make_env("ClutterReach-v0")
    env.reset(seed=SHELF_SEED)
    scene = env.unwrapped.scene
    planner = JointPlannerReacher(env)
    planner.checker.set_obstacles(scene.obstacles)
    path = planner.plan(np.array(scene.start), np.array(scene.target))
    assert path is not None and len(path) > 2  # the straight line is blocked: the search had to work
    assert np.allclose(path[0], scene.start)
    assert np.linalg.norm(planner.checker.ee_positions(path[-1])[0] - scene.target) <= GOAL_BALL + 0.006
    touching = ConfigurationChecker(margin=1e-3)  # the env's contact tolerance
    touching.set_obstacles(scene.obstacles)
    for a, b in zip(path[:-1], path[1:]):
        n = int(np.ceil(np.abs(b - a).max() / 0.006))
        assert touching.free(a + (b - a) * (np.arange(n + 1) / n)[:, None]).all()


def test_reference_reaches_seeded_layouts_without_contact(make_env):
    env = make_env("ClutterReach-v0")
    planner = JointPlannerReacher(env)
    for seed in range(SHELF_SEED, SHELF_SEED + 4):
        obs, _ = env.reset(seed=seed)
        cost, done = 0.0, False
        while not done:
            obs, _, terminated, truncated, info = env.step(planner(obs))
            cost += info["cost"]
            done = terminated or truncated
        assert info["is_success"] and cost == 0.0, seed
    assert planner.planned == 4 and planner.failed == 0


def test_reference_needs_joint_velocity_control(make_env):
    with pytest.raises(ValueError, match="joint_velocity"):
        JointPlannerReacher(make_env("ClutterReach-v0", control="ee_position"))


def test_time_parameterisation_keeps_every_joint_under_its_speed():
    speed = np.array([0.05] * 4 + [0.06] * 3)
    path = np.array([READY, READY + [0.5, -0.2, 0, 0, 0.3, 0, 0], READY])
    ref = _time_parameterise(path, speed)
    assert np.allclose(ref[0], path[0]) and np.allclose(ref[-1], path[-1])
    assert np.all(np.abs(np.diff(ref, axis=0)) <= speed + 1e-12)
    assert any(np.allclose(r, path[1]) for r in ref)  # waypoints are visited, not cut
