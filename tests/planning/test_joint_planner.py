"""The joint-space planner and the ClutterReach reference that tracks it: IK against the simulator's forward
kinematics, the clearance margin, collision-free paths checked finer than they were planned, clean reaches in the
env, and walking a path by arc length."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import SHELF_SEED

from clutter_gym.datatypes import Obstacle
from clutter_gym.planning.joint_space import (
    GOAL_BALL,
    ArmPlanner,
    ConfigurationChecker,
    inverse_kinematics,
    time_parameterise,
)
from clutter_gym.planning.path import JointPath
from clutter_gym.training.joint_planner import JointPlannerReacher

READY = np.array([0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4])


@pytest.fixture(scope="module")
def checker():
    return ConfigurationChecker()


def test_ik_solutions_put_the_simulated_end_effector_on_the_target(checker, make_env):
    target = np.array([0.45, -0.2, 0.25])
    seeds = np.random.default_rng(0).uniform(-1.0, 1.0, (16, 7)) + READY
    solutions = inverse_kinematics(checker, target, seeds)
    assert len(solutions) >= 4
    env = make_env("ClutterReach-v1")
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
    env = make_env("ClutterReach-v1")
    env.reset(seed=SHELF_SEED)
    scene = env.unwrapped.scene
    planner = ArmPlanner()
    path = planner.plan(scene.obstacles, np.array(scene.start), np.array(scene.target), np.random.default_rng(0))
    assert path is not None and len(path) > 2  # the straight line is blocked: the search had to work
    assert np.allclose(path[0], scene.start)
    assert np.linalg.norm(planner.checker.ee_positions(path[-1])[0] - scene.target) <= GOAL_BALL + 0.006
    touching = ConfigurationChecker(margin=1e-3)  # the env's contact tolerance
    touching.set_obstacles(scene.obstacles)
    for a, b in zip(path[:-1], path[1:]):
        n = int(np.ceil(np.abs(b - a).max() / 0.006))
        assert touching.free(a + (b - a) * (np.arange(n + 1) / n)[:, None]).all()


def test_reference_reaches_seeded_layouts_without_contact(make_env):
    env = make_env("ClutterReach-v1")
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
        JointPlannerReacher(make_env("ClutterReach-v1", control="ee_position"))


def test_time_parameterisation_keeps_every_joint_under_its_speed():
    speed = np.array([0.05] * 4 + [0.06] * 3)
    path = np.array([READY, READY + [0.5, -0.2, 0, 0, 0.3, 0, 0], READY])
    ref = time_parameterise(path, speed)
    assert np.allclose(ref[0], path[0]) and np.allclose(ref[-1], path[-1])
    assert np.all(np.abs(np.diff(ref, axis=0)) <= speed + 1e-12)
    assert any(np.allclose(r, path[1]) for r in ref)  # waypoints are visited, not cut


def test_analytic_jacobian_matches_finite_differences(checker):
    q = np.random.default_rng(1).uniform(-1.0, 1.0, (20, 7)) + READY
    p, jac = checker.ee_jacobian(q)
    eps = 1e-6
    numeric = np.stack([(checker.ee_positions(q + eps * np.eye(7)[i]) - p) / eps for i in range(7)], axis=-1)
    assert np.abs(jac - numeric).max() < 1e-5  # finite-difference truncation is ~1e-6 at this step


def test_joint_path_walks_by_arc_length():
    path = JointPath(np.array([np.zeros(7), [1.0, 0, 0, 0, 0, 0, 0], [1.0, 1.0, 0, 0, 0, 0, 0]]))
    assert path.length == pytest.approx(2.0)
    assert np.allclose(path.waypoint(0.5), [0.5, 0, 0, 0, 0, 0, 0], atol=0.03)
    assert np.allclose(path.waypoint(1.5), [1.0, 0.5, 0, 0, 0, 0, 0], atol=0.03)
    assert np.allclose(path.waypoint(5.0), [1.0, 1.0, 0, 0, 0, 0, 0])  # beyond the end: the end
    path.advance(np.array([1.0, 0.2, 0, 0, 0, 0, 0]), window=0.5)  # out of reach of the window: stops at its edge
    assert path.arc[path.index] == pytest.approx(0.5, abs=0.03)
    path.advance(np.array([1.0, 0.2, 0, 0, 0, 0, 0]), window=1.0)
    assert np.allclose(path.points[path.index], [1.0, 0.2, 0, 0, 0, 0, 0], atol=0.03)
    path.advance(np.zeros(7), window=1.0)  # never back
    assert path.arc[path.index] == pytest.approx(1.2, abs=0.03)


def test_subgoal_points_along_the_planned_path(make_env):
    env = make_env("ClutterReach-v1", subgoal_lookahead=0.2)
    obs, _ = env.reset(seed=SHELF_SEED)
    task = env.unwrapped.task
    assert task.path is not None and task.path.length > 0.5
    q = obs["joint_position"].astype(float)
    assert np.allclose(task.path.points[0], q, atol=1e-5)  # planned from where the arm stands
    assert np.linalg.norm(obs["subgoal"]) == pytest.approx(0.2, abs=0.031)  # one path resolution step
    assert np.allclose(q + obs["subgoal"], task.path.waypoint(0.2), atol=1e-6)
    speed = env.unwrapped.robot.speed * env.unwrapped.robot.control_dt
    start_distance = np.linalg.norm(obs["ee_position"] - obs["target"])
    progress, done = 0.0, False
    while not done:  # pure pursuit of the subgoal reaches the shelf target
        obs, _, terminated, truncated, info = env.step(np.clip(obs["subgoal"] / speed, -1.0, 1.0))
        progress += info["reward_terms"]["progress"]
        done = terminated or truncated
    assert info["is_success"]
    # progress is paid along the path, and the whole path pays what the straight distance would: the sum
    # telescopes to the straight distance minus what is left at the end, at most the path end's goal ball plus
    # the success radius (10 per metre)
    assert progress == pytest.approx(10.0 * start_distance, abs=10.0 * (GOAL_BALL + 0.05))


def test_subgoal_is_seeded_by_the_layout_and_planned_once_per_layout(make_env):
    env = make_env("ClutterReach-v1", subgoal_lookahead=0.2)
    first, _ = env.reset(seed=SHELF_SEED)
    checker = env.unwrapped.task.planner.checker
    checks = checker.checks
    again, _ = env.reset(seed=SHELF_SEED)
    assert checker.checks == checks  # the cached plan
    assert np.array_equal(first["subgoal"], again["subgoal"])
    other = make_env("ClutterReach-v1", subgoal_lookahead=0.2)
    fresh, _ = other.reset(seed=SHELF_SEED)  # a new env plans the same path from the same layout
    assert np.array_equal(first["subgoal"], fresh["subgoal"])
    assert "subgoal" not in make_env("ClutterReach-v1").observation_space.spaces


@pytest.mark.parametrize("value", [-0.1, 3.5, float("nan")])
def test_subgoal_lookahead_out_of_range_is_refused(make_env, value):
    with pytest.raises(ValueError, match=r"subgoal_lookahead must be in \[0, 3\] radians"):
        make_env("ClutterReach-v1", subgoal_lookahead=value)
