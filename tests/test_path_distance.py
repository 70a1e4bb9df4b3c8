"""The path-distance field behind ClutterNav's progress reward, against distances known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.worlds.clutter import ClutterSpec, sample_scene
from clutter_gym.worlds.path_distance import PathDistance
from clutter_gym.worlds.scene import Obstacle, Scene

SPEC = ClutterSpec(arena_size=6.0)
R = 0.17  # the diffbot's footprint radius


@pytest.mark.parametrize("goal", [(2.0, 1.5), (2.2, -0.3), (0.5, 2.5), (-2.4, 2.4)])
def test_in_an_empty_arena_it_is_the_straight_line_within_the_grid_error(goal):
    field = PathDistance(Scene((), (0.0, 0.0, 0.0), goal), SPEC, R)
    for start in [(-2.0, -1.0), (0.03, -2.2), (1.0, 1.0)]:
        straight = math.dist(start, goal)
        # 16-neighbour paths are at most 2.7% longer than the straight line, plus half a cell at each end.
        assert straight <= field(*start) <= 1.027 * straight + SPEC.resolution


def test_a_wall_across_the_way_makes_the_path_go_around_it():
    # A wall from y = -3 (the arena wall) up to y = 1 at x = 0: from (-1, 0) to (1, 0) the shortest path for a
    # disc of radius R passes the wall's top corners at (+-0.05, 1): length 2 * hypot(0.95, 1) + 0.1, plus the
    # clearance R the disc keeps around the corners (bounded by the arc length pi * R).
    wall = Obstacle("box", (0.1, 4.0, 0.5), (0.0, -1.0), 0.0)
    field = PathDistance(Scene((wall,), (-1.0, 0.0, 0.0), (1.0, 0.0)), SPEC, R)
    around = 2 * math.hypot(0.95, 1.0) + 0.1
    assert around < field(-1.0, 0.0) < around + math.pi * R + 2 * SPEC.resolution
    assert field(-1.0, 0.0) > 1.4 * 2.0  # far longer than the straight line


def test_the_field_is_finite_everywhere_and_zero_at_the_goal():
    rng = np.random.default_rng(4)
    for _ in range(5):
        scene = sample_scene(rng, SPEC, R)
        field = PathDistance(scene, SPEC, R)
        assert np.all(np.isfinite(field.values))
        assert field(*scene.goal) == pytest.approx(0.0, abs=SPEC.resolution)
        assert field(*scene.start[:2]) >= math.dist(scene.start[:2], scene.goal) - 1e-9


def test_progress_reward_follows_the_path_not_the_straight_line():
    import gymnasium as gym

    wall = {"shape": "box", "size": [0.1, 4.0, 0.5], "position": [0.0, -1.0]}
    scene = {"obstacles": [wall], "start": [-1.0, 0.0, math.pi / 2], "goal": [1.0, 0.0]}
    env = gym.make("ClutterNav-v0")
    env.reset(seed=0, options={"scene": scene})
    # Driving +y (away from the goal in straight-line terms, but along the path around the wall) earns progress.
    progress = 0.0
    for _ in range(10):
        _, _, _, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        progress += info["reward_terms"]["progress"]
    env.close()
    assert progress > 0.5
