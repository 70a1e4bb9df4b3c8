"""The path-distance field behind ClutterNav's progress reward, against distances known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from clutter_gym.datatypes import Obstacle
from clutter_gym.tasks.navigate import SUBGOAL_PLAN_MARGIN
from clutter_gym.worlds.floor.grid import clearance_field
from clutter_gym.worlds.floor.path import _MOVES, PathDistance, _dijkstra_from
from clutter_gym.worlds.floor.sample import sample_scene
from clutter_gym.worlds.floor.scene import Scene
from clutter_gym.worlds.floor.spec import ClutterSpec

SPEC = ClutterSpec(arena_size=6.0)
R = 0.17  # the diffbot's footprint radius
#: Every move of the 16-neighbourhood, both ways, and the cells its segment crosses (steps from its start).
_CROSSED = dict(_MOVES + tuple(((-a, -b), tuple((ta - a, tb - b) for ta, tb in t)) for (a, b), t in _MOVES))


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
    env = gym.make("ClutterNav-v1")
    env.reset(seed=0, options={"scene": scene})
    # Driving +y (away from the goal in straight-line terms, but along the path around the wall) earns progress.
    progress = 0.0
    for _ in range(10):
        _, _, _, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        progress += info["reward_terms"]["progress"]
    env.close()
    assert progress > 0.5


# -- the subgoal: a point a fixed length ahead on the same shortest path -----------------------------------------

def test_in_an_empty_arena_the_waypoint_lies_on_the_straight_line():
    goal = (2.0, 1.5)
    field = PathDistance(Scene((), (0.0, 0.0, 0.0), goal), SPEC, R, plan_margin=0.25)
    start = (-2.0, -1.0)
    point = field.waypoint(*start, lookahead=1.0)
    # A grid path runs through cell centres, and the search picks one of several equally short orders of its
    # moves (here diagonal steps first, straight ones later), so it strays from the straight line by up to a
    # couple of cells and a lookahead of 1 m of path ends short of 1 m along the line (0.84 m here).
    direction = np.subtract(goal, start) / math.dist(start, goal)
    offset = np.subtract(point, start)
    assert abs(direction[0] * offset[1] - direction[1] * offset[0]) < 2 * SPEC.resolution
    assert 0.8 < float(offset @ direction) <= 1.0 + 1e-9


def test_near_the_goal_the_waypoint_is_the_goal():
    goal = (2.0, 1.5)
    field = PathDistance(Scene((), (0.0, 0.0, 0.0), goal), SPEC, R, plan_margin=0.25)
    assert field.waypoint(1.6, 1.3, lookahead=1.0) == pytest.approx(goal)
    with pytest.raises(RuntimeError, match="plan_margin"):
        PathDistance(Scene((), (0.0, 0.0, 0.0), goal), SPEC, R).waypoint(0.0, 0.0, lookahead=1.0)


def test_at_no_lookahead_the_waypoint_is_the_point_and_a_point_has_two_coordinates():
    field = PathDistance(Scene((), (0.0, 0.0, 0.0), (2.0, 1.5)), SPEC, R, plan_margin=0.25)
    centre = (float(SPEC.cell_centres[30]), float(SPEC.cell_centres[40]))  # its path's first step is 0 m long
    assert field.path(*centre)[1] == pytest.approx(centre, abs=0.0)
    assert field.waypoint(*centre, lookahead=0.0) == centre
    with pytest.raises(ValueError, match="2 coordinates"):
        field.path(0.0, 0.0, 1.0)


def test_the_waypoint_leads_around_a_wall_and_keeps_the_footprint_free():
    # The wall of test_a_wall_across_the_way...: from (-1, 0) the path to (1, 0) first climbs to the wall's top.
    wall = Obstacle("box", (0.1, 4.0, 0.5), (0.0, -1.0), 0.0)
    field = PathDistance(Scene((wall,), (-1.0, 0.0, 0.0), (1.0, 0.0)), SPEC, R, plan_margin=0.25)
    point = field.waypoint(-1.0, 0.0, lookahead=1.0)
    assert point[1] > 0.5  # heads up towards the corner, not at the goal through the wall
    assert point[0] < -0.05 - R + SPEC.resolution  # still on the start's side, a footprint off the wall
    # Walking waypoint to waypoint reaches the goal; the planner rounds the wall's top a margin wider than the
    # shortest path does, and every waypoint keeps the footprint plus most of the margin off the wall.
    position, walked, closest = (-1.0, 0.0), 0.0, math.inf
    for _ in range(20):
        nxt = field.waypoint(*position, lookahead=0.5)
        walked += math.dist(position, nxt)
        position = nxt
        closest = min(closest, _box_distance(position, centre=(0.0, -1.0), half=(0.05, 2.0)))
    assert position == pytest.approx((1.0, 0.0))
    assert field(-1.0, 0.0) - SPEC.resolution < walked < field(-1.0, 0.0) + 2 * math.pi * 0.25
    assert closest > R + 0.15


def test_the_subgoal_observation_points_at_the_waypoint_in_the_robot_frame():
    import gymnasium as gym

    wall = {"shape": "box", "size": [0.1, 4.0, 0.5], "position": [0.0, -1.0]}
    scene = {"obstacles": [wall], "start": [-1.0, 0.0, 0.0], "goal": [1.0, 0.0]}
    env = gym.make("ClutterNav-v1", subgoal_lookahead=1.0)
    obs, _ = env.reset(seed=0, options={"scene": scene})
    field = PathDistance(Scene((Obstacle("box", (0.1, 4.0, 0.5), (0.0, -1.0), 0.0),), (-1.0, 0.0, 0.0), (1.0, 0.0)),
                         SPEC, R, plan_margin=SUBGOAL_PLAN_MARGIN)
    x, y = env.unwrapped.robot.state().position[:2]
    yaw = env.unwrapped.robot.state().yaw
    px, py = field.waypoint(x, y, lookahead=1.0)
    bearing = math.atan2(py - y, px - x) - yaw
    np.testing.assert_allclose(obs["subgoal"], [math.hypot(px - x, py - y), math.sin(bearing), math.cos(bearing)],
                               atol=1e-5)
    assert obs["subgoal"][1] > 0.7  # the waypoint is to the robot's left (+y), while the goal is straight ahead
    assert obs["goal"][2] > 0.99
    assert env.observation_space["subgoal"].contains(obs["subgoal"])
    env.close()


def test_the_subgoal_entry_is_opt_in_and_its_lookahead_is_checked():
    import gymnasium as gym

    env = gym.make("ClutterNav-v1")
    assert "subgoal" not in env.observation_space.spaces
    env.close()
    with pytest.raises(ValueError, match="subgoal_lookahead must be in"):
        gym.make("ClutterNav-v1", subgoal_lookahead=-1.0)


# -- the search and the field it starts from, against straightforward versions of them ---------------------------

def test_the_search_gives_scipys_distances_on_the_listed_edges_bit_for_bit():
    """Distances equal those of scipy's Dijkstra on the explicit graph of the same 16-neighbourhood edges, bit for
    bit, with and without a costmap; every next cell is a free move whose weight gives the distance exactly (where
    equally short paths tie, the search picks one by its own rule, not scipy's)."""
    rng = np.random.default_rng(11)
    n = len(SPEC.cell_centres)
    for _ in range(6):
        scene = sample_scene(rng, SPEC, R)
        clearance = clearance_field(scene.obstacles, SPEC, cap=0.5)
        free = clearance > R
        free[30, 30] = True
        for cost in (None, 1.0 + rng.uniform(0.0, 4.0, free.shape)):
            distance, after = _dijkstra_from((30, 30), clearance, R, SPEC.resolution, cost)
            reference = _undirected_search((30, 30), free, SPEC.resolution, cost)
            np.testing.assert_array_equal(distance, reference)
            reached = np.flatnonzero(np.isfinite(distance).ravel())
            assert reached.size > 1000
            flat = distance.ravel()
            for cell in reached[reached != 30 * n + 30]:
                nxt = int(after[cell])
                move = (nxt // n - cell // n, nxt % n - cell % n)
                assert all(free[cell // n + di, cell % n + dj] for di, dj in _CROSSED[move])
                weight = SPEC.resolution * math.hypot(*move)
                if cost is not None:
                    weight *= 0.5 * (cost.ravel()[cell] + cost.ravel()[nxt])
                assert flat[cell] == flat[nxt] + weight


def test_a_generated_scene_gives_the_field_of_its_bare_layout():
    """The clearance field a generated scene keeps gives bit for bit the field computed from the layout alone."""
    rng = np.random.default_rng(8)
    for _ in range(5):
        scene = sample_scene(rng, SPEC, R)
        bare = Scene(scene.obstacles, scene.start, scene.goal)
        assert scene.clearance_grid is not None and bare == scene
        for margin in (None, SUBGOAL_PLAN_MARGIN):
            kept, fresh = PathDistance(scene, SPEC, R, margin), PathDistance(bare, SPEC, R, margin)
            np.testing.assert_array_equal(kept.values, fresh.values)
            if margin is not None:
                np.testing.assert_array_equal(kept.path(*scene.start[:2]), fresh.path(*scene.start[:2]))


def _undirected_search(source, free, res, cost):
    """Shortest paths from ``source`` on the half graph: one stored edge per forward move."""
    n = free.shape[0]
    padded = np.pad(free, 2)
    rows, cols, weights = [], [], []
    for (di, dj), through in _MOVES:
        ok = free & padded[2 + di:2 + di + n, 2 + dj:2 + dj + n]
        for ti, tj in through:
            ok &= padded[2 + ti:2 + ti + n, 2 + tj:2 + tj + n]
        ids = np.flatnonzero(ok)
        weight = np.full(ids.size, res * math.hypot(di, dj))
        if cost is not None:
            weight *= 0.5 * (cost.ravel()[ids] + cost.ravel()[ids + di * n + dj])
        rows.append(ids)
        cols.append(ids + di * n + dj)
        weights.append(weight)
    graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(n * n, n * n))
    return dijkstra(graph.tocsr(), directed=False, indices=source[0] * n + source[1]).reshape(n, n)


def _box_distance(point: tuple[float, float], centre: tuple[float, float], half: tuple[float, float]) -> float:
    qx, qy = abs(point[0] - centre[0]) - half[0], abs(point[1] - centre[1]) - half[1]
    return math.hypot(max(qx, 0.0), max(qy, 0.0)) + min(max(qx, qy), 0.0)
