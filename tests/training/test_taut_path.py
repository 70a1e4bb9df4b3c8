"""ClutterFly-v1's taut teacher: the farthest point of the planned path in sight, and a label that no longer turns
with the drone's place in its grid cell."""

from __future__ import annotations

import dataclasses
import math

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym.training.taut_path import REACH, taut_point
from clutter_gym.training.teachers import make_teacher


def direction_spread(labels: np.ndarray) -> float:
    """Radians: the mean angle between each of ``labels`` ((n, 2) azimuth / pi, elevation / (pi / 2)) and their
    mean direction, a measure of how much the label of one state moves with the drone's place in its cell."""
    azimuth, elevation = labels[:, 0] * math.pi, labels[:, 1] * math.pi / 2
    vectors = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                        np.sin(elevation)], axis=1)
    mean = vectors.mean(axis=0)
    mean /= max(float(np.linalg.norm(mean)), 1e-12)
    return float(np.mean(np.arccos(np.clip(vectors @ mean, -1.0, 1.0))))


def _open(points: np.ndarray) -> np.ndarray:
    return np.ones(len(points))


def test_in_the_open_it_points_at_the_path_reach_metres_along():
    path = np.array([[0.0, 0.0, 1.0], [0.1, 0.1, 1.0], [1.0, 0.1, 1.0], [3.0, 0.1, 1.0]])
    point = taut_point(path, _open)
    lengths = np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))
    assert point == pytest.approx([1.0 + (REACH - lengths[1]), 0.1, 1.0])  # REACH along the path, on its last leg
    assert taut_point(path[:3], _open) == pytest.approx(path[2])  # a path shorter than the reach: its end


def test_it_stops_at_the_last_point_seen_before_a_wall_in_the_way():
    # the path rounds a wall standing at x = 1 below y = 0.3: up the wall's near side, round its end, down behind it
    path = np.array([[0.0, 0.0, 1.0], [0.5, 0.2, 1.0], [0.5, 0.6, 1.0], [1.3, 0.6, 1.0], [1.3, -1.0, 1.0]])

    def clearance(points: np.ndarray) -> np.ndarray:
        inside = (np.abs(points[:, 0] - 1.0) < 0.05) & (points[:, 1] < 0.3)
        return np.where(inside, -1.0, 1.0)

    assert taut_point(path, clearance) == pytest.approx(path[3])  # the corner past the wall's end, not beyond it
    assert taut_point(path, lambda p: -np.ones(len(p))) == pytest.approx(path[1])  # nothing in sight: the next point


@pytest.fixture
def fly_env():
    env = gym.make("ClutterFly-v1", sensors=["lidar"], subgoal_lookahead=0.5, obstacle_density=0.05)
    yield env
    env.close()


def test_the_taut_label_moves_less_than_the_planners_as_the_drone_moves_inside_its_cell(fly_env):
    u = fly_env.unwrapped
    teachers = {name: make_teacher("ClutterFly-v1", name, fly_env, "waypoint") for name in ("planner", "taut")}
    rng = np.random.default_rng(0)
    spreads: dict[str, list[float]] = {"planner": [], "taut": []}
    for episode in range(4):
        obs, info = fly_env.reset(seed=10 + episode)
        state = u.robot.state()
        for name, teacher in teachers.items():
            labels = []
            for _ in range(10):
                p = np.asarray(state.position) + rng.uniform(-0.08, 0.08, 3)
                moved = dataclasses.replace(state, position=p)
                u.robot.state = lambda moved=moved: moved  # the teachers read the drone's pose here
                sub = u.task._path_distance.waypoint(*p.tolist(), lookahead=0.5)
                labels.append(teacher({**obs, "subgoal": state.rotation.T @ (np.asarray(sub) - p)}, info))
                del u.robot.state
            spreads[name].append(direction_spread(np.array(labels)))
    assert np.mean(spreads["taut"]) < 0.5 * np.mean(spreads["planner"])


def test_the_taut_teacher_answers_in_the_planners_units_and_points_along_its_path(fly_env):
    obs, info = fly_env.reset(seed=3)
    taut = make_teacher("ClutterFly-v1", "taut", fly_env, "waypoint")(obs, info)
    planner = make_teacher("ClutterFly-v1", "planner", fly_env, "waypoint")(obs, info)
    assert taut.shape == planner.shape == (2,) and np.all(np.abs(taut) <= 1.0)
    vectors = [np.array([math.cos(e * math.pi / 2) * math.cos(a * math.pi), math.cos(e * math.pi / 2)
                         * math.sin(a * math.pi), math.sin(e * math.pi / 2)]) for a, e in (taut, planner)]
    assert math.degrees(math.acos(np.clip(vectors[0] @ vectors[1], -1, 1))) < 60.0  # the same way round
    velocity = make_teacher("ClutterFly-v1", "taut", fly_env)(obs, info)  # the velocity space: top speed's units
    assert velocity.shape == (3,) and np.all(np.isfinite(velocity))
