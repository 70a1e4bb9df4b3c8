"""The line-up paths into a shelf: which targets are covered, the hand's pose from the pose IK against the forward
kinematics, the insertion along its line and clear, and the ``line-up`` teacher reaching a shelf target in the
env."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import SHELF_SEED

from clutter_gym.datatypes import Obstacle
from clutter_gym.planning.hand_pose import approach_axis, hand_axis
from clutter_gym.planning.line_up import INSERT_MARGIN, PITCHES, SHORT, STANDOFF, LineUpPlanner, covered
from clutter_gym.planning.path import JointPath
from clutter_gym.training.teachers import make_teacher
from clutter_gym.worlds.table.sample import shelf_parts

READY = np.array([0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4])
SHELF_ANGLE = 0.8  # radians: the shelf's bearing from the base, as a sampled layout places it (0.35..1.45)
SHELF = shelf_parts((0.6 * math.cos(SHELF_ANGLE), 0.6 * math.sin(SHELF_ANGLE)), SHELF_ANGLE)


@pytest.fixture(scope="module")
def planner():
    return LineUpPlanner()


def compartment(low: float, high: float) -> np.ndarray:
    """The centre of a compartment of :data:`SHELF`, as the layout sampler places targets in one."""
    inner = 0.58 * np.array([math.cos(SHELF_ANGLE), math.sin(SHELF_ANGLE)])
    return np.array([*inner, 0.5 * (low + high)])


def test_covered_means_something_stands_above_the_target():
    assert covered(compartment(0.0, 0.2), SHELF) and covered(compartment(0.22, 0.45), SHELF)
    assert not covered(compartment(0.0, 0.2) + [0.0, 0.0, 0.5], SHELF)  # above the shelf's top
    assert not covered(np.array([0.3, -0.3, 0.2]), SHELF)  # beside it
    box, can = Obstacle("box", (0.1, 0.4, 0.1), (0.5, 0.0), math.pi / 2, z=0.3), Obstacle(
        "cylinder", (0.1, 0.1, 0.1), (0.0, 0.5), z=0.3)
    assert covered(np.array([0.5, 0.0, 0.1]), [box]) and covered(np.array([0.5 + 0.15, 0.0, 0.1]), [box])
    assert not covered(np.array([0.5, 0.15, 0.1]), [box])  # the box is turned: 0.4 m along x, 0.1 m along y
    assert covered(np.array([0.04, 0.5, 0.2]), [can]) and not covered(np.array([0.06, 0.5, 0.2]), [can])


def test_the_hand_pose_solution_puts_the_hand_at_the_point_along_the_axis_with_its_fingers_level(planner):
    point = np.array([0.5, -0.1, 0.3])
    axis = hand_axis(point, PITCHES[2])
    seeds = READY + np.random.default_rng(0).normal(0.0, 0.3, (16, 7))
    solved = planner.hand.solve(point, axis, seeds)
    good = solved[~np.isnan(solved).any(axis=1)]
    assert len(good) >= 4  # of 16 seeds around the ready pose
    frame = planner.checker.frames(good)[planner.checker.arm.ee_link]
    np.testing.assert_allclose(frame[:, :3, 3], np.broadcast_to(point, (len(good), 3)), atol=0.005)
    np.testing.assert_allclose(frame[:, :3, 2], np.broadcast_to(axis, (len(good), 3)), atol=0.005)
    np.testing.assert_allclose(frame[:, 2, 1], 0.0, atol=0.005)  # the fingers open horizontally
    assert np.all(good >= planner.checker.lower) and np.all(good <= planner.checker.upper)


@pytest.mark.parametrize("low, high", [(0.0, 0.2), (0.22, 0.45)])
def test_the_insertion_runs_straight_along_the_approach_axis_and_stays_clear(planner, low, high):
    target = compartment(low, high)
    planner.checker.set_obstacles(SHELF)
    path = planner.insertion(READY, target)
    assert path is not None
    way = approach_axis(target)
    ee = planner.checker.ee_positions(JointPath(path).points)  # the walked path, every 0.03 rad
    along = (ee - target) @ way
    assert along[0] == pytest.approx(-SHORT - STANDOFF, abs=0.005)
    assert along[-1] == pytest.approx(-SHORT, abs=0.005)
    assert np.all(np.diff(along) > -1e-3)  # never backs out
    lateral = (ee - target) - along[:, None] * way
    assert np.abs(lateral).max() < 0.01  # joint-space interpolation between IK points 4 cm apart
    pitch = math.asin(-planner.checker.frames(path[-1:])[planner.checker.arm.ee_link][0, 2, 2])
    assert min(abs(pitch - p) for p in PITCHES) < 0.01
    assert min(planner.checker.clearance(q) for q in JointPath(path).points) >= INSERT_MARGIN


def test_a_target_in_the_open_gets_the_planners_own_path(planner):
    target = np.array([0.45, -0.2, 0.25])
    path = planner.plan(SHELF, READY, target, np.random.default_rng(0))
    assert path is not None and len(path) == 2  # the straight line the planner tries first


def test_the_line_up_teacher_reaches_a_shelf_target_cleanly(make_env):
    env = make_env("ClutterReach-v1", observe_directions=True)
    teacher = make_teacher("ClutterReach-v1", "line-up", env)
    obs, info = env.reset(seed=SHELF_SEED)
    scene = env.unwrapped.scene
    assert covered(np.array(scene.target), scene.obstacles)
    teacher.reset()
    for _ in range(env.spec.max_episode_steps):
        action = teacher(obs, info)
        assert action.shape == (7,) and np.all(np.abs(action) <= 1.0)
        obs, _, terminated, truncated, info = env.step(action)
        assert info["cost"] == 0.0
        if terminated or truncated:
            break
    assert info["is_success"]
