"""Seeded floor layouts: density, spawn clearance, determinism, and the reachability guarantee checked independently."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

import clutter_gym.worlds.floor.sample
from clutter_gym.worlds.floor.grid import clearance_field
from clutter_gym.worlds.floor.sample import sample_scene
from clutter_gym.worlds.floor.spec import ClutterSpec

ROBOT_RADIUS = 0.17


def exact_clearance(scene, spec: ClutterSpec, xs: np.ndarray) -> np.ndarray:
    """Distance to the nearest footprint or wall on the grid xs x xs, straight from the analytic shapes."""
    x, y = xs[:, None], xs[None, :]
    d = np.minimum(0.5 * spec.arena_size - np.abs(x), 0.5 * spec.arena_size - np.abs(y))
    for o in scene.obstacles:
        d = np.minimum(d, o.distance(x, y))
    return d


@pytest.mark.parametrize("density", [0.05, 0.12, 0.25])
def test_goal_is_reachable_on_an_independent_fine_grid(density):
    """Every layout's start and goal are joined by cells whose exact clearance exceeds the footprint radius."""
    spec = ClutterSpec(obstacle_density=density)
    rng = np.random.default_rng(123)
    step = 0.02
    xs = np.arange(-0.5 * spec.arena_size + step / 2, 0.5 * spec.arena_size, step)
    for _ in range(15):
        scene = sample_scene(rng, spec, ROBOT_RADIUS)
        labels, _ = ndimage.label(exact_clearance(scene, spec, xs) > ROBOT_RADIUS)
        start = labels[np.abs(xs - scene.start[0]).argmin(), np.abs(xs - scene.start[1]).argmin()]
        goal = labels[np.abs(xs - scene.goal[0]).argmin(), np.abs(xs - scene.goal[1]).argmin()]
        assert start != 0 and start == goal


def test_corridor_layouts_are_reachable_on_an_independent_fine_grid(monkeypatch):
    """The corridor the generator keeps clear at high density (forced from the first attempt here) joins start and
    goal, and the density is still met."""
    monkeypatch.setattr(clutter_gym.worlds.floor.sample, "PLAIN_ATTEMPTS", 0)
    spec = ClutterSpec(obstacle_density=0.3)
    rng = np.random.default_rng(7)
    step = 0.02
    xs = np.arange(-0.5 * spec.arena_size + step / 2, 0.5 * spec.arena_size, step)
    for _ in range(15):
        scene = sample_scene(rng, spec, ROBOT_RADIUS)
        assert_valid(scene, spec)
        labels, _ = ndimage.label(exact_clearance(scene, spec, xs) > ROBOT_RADIUS)
        start = labels[np.abs(xs - scene.start[0]).argmin(), np.abs(xs - scene.start[1]).argmin()]
        goal = labels[np.abs(xs - scene.goal[0]).argmin(), np.abs(xs - scene.goal[1]).argmin()]
        assert start != 0 and start == goal


def assert_valid(scene, spec: ClutterSpec) -> None:
    """Density met, start and goal clear by the spawn clearance and far enough apart."""
    assert sum(o.area for o in scene.obstacles) >= spec.obstacle_density * spec.arena_size**2
    for point in (scene.start[:2], scene.goal):
        assert scene.clearance(*point, spec.arena_size) > ROBOT_RADIUS + spec.spawn_clearance
    distance = np.hypot(scene.goal[0] - scene.start[0], scene.goal[1] - scene.start[1])
    assert distance >= spec.min_goal_distance * spec.arena_size


def test_layouts_meet_density_spawn_clearance_and_goal_distance():
    spec = ClutterSpec(obstacle_density=0.15)
    rng = np.random.default_rng(5)
    for _ in range(30):
        assert_valid(sample_scene(rng, spec, ROBOT_RADIUS), spec)


@pytest.mark.parametrize("arena", [2.0, 15.0, 30.0])
def test_the_densest_clutter_builds_in_every_arena_size(arena):
    """At density 0.3 no free component spans a 15 or 30 m arena: only the kept corridor makes these work."""
    spec = ClutterSpec(arena_size=arena, obstacle_density=0.3)
    rng = np.random.default_rng(0)
    for _ in range(2):
        assert_valid(sample_scene(rng, spec, ROBOT_RADIUS), spec)


def test_generated_shapes_come_from_a_small_catalogue():
    """3 levels per range: boxes (a >= b) 6 shapes, cylinders 3, wall segments 3."""
    rng = np.random.default_rng(0)
    shapes = {(o.shape, *o.size) for _ in range(200) for o in sample_scene(rng, ClutterSpec(), ROBOT_RADIUS).obstacles}
    assert len(shapes) == 12
    assert {s[1] for s in shapes if s[0] == "cylinder"} == {0.2, 0.4, 0.6}  # diameters of radii 0.1, 0.2, 0.3


def test_density_zero_gives_an_empty_arena():
    scene = sample_scene(np.random.default_rng(0), ClutterSpec(obstacle_density=0.0), ROBOT_RADIUS)
    assert scene.obstacles == ()


def test_same_seed_same_layout():
    a = sample_scene(np.random.default_rng(9), ClutterSpec(), ROBOT_RADIUS)
    b = sample_scene(np.random.default_rng(9), ClutterSpec(), ROBOT_RADIUS)
    assert a == b


def test_clearance_field_matches_the_exact_distance():
    spec = ClutterSpec(obstacle_density=0.2)
    rng = np.random.default_rng(1)
    cap = 0.45
    for _ in range(5):
        scene = sample_scene(rng, spec, ROBOT_RADIUS)
        field = clearance_field(scene.obstacles, spec, cap)
        exact = np.minimum(exact_clearance(scene, spec, spec.cell_centres), cap)
        np.testing.assert_allclose(field, exact, atol=1e-12)


def test_impossible_density_for_the_robot_raises_a_clear_error():
    spec = ClutterSpec(arena_size=2.0, obstacle_density=0.3, max_attempts=3)
    with pytest.raises(RuntimeError, match="lower the density or enlarge the arena"):
        sample_scene(np.random.default_rng(0), spec, robot_radius=0.6)
