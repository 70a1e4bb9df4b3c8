"""Large scenes are searched near the robot first: the k-d tree answers what a pass over every obstacle answers, and
a search widened only where it cannot prove a shape's answer exact reports what a search of every obstacle does
(clearances, obstacles, witness points, contacts, swept hits), for per-link and nearest-pair checkers alike."""

from __future__ import annotations

import numpy as np
import pytest

import clutter_gym.collision.nearest as nearest_module
from clutter_gym.collision import (
    CollisionChecker,
    RobotCollisionModel,
    UrdfKinematics,
    build_link_shapes,
    load_collision_elements,
)
from clutter_gym.collision.bounds import ObstacleBounds
from clutter_gym.collision.nearest import FIRST_SEARCH, SMALL_SCENE
from clutter_gym.datatypes import LinkStates, Obstacle, RobotState
from clutter_gym.robots import PandaArm

URDF = PandaArm().urdf_path
KIN = UrdfKinematics(URDF)
FINGERS = [0.02, 0.02]
LIMITS = np.array([[-2.8, 2.8], [-1.7, 1.7], [-2.8, 2.8], [-3.0, -0.1], [-2.8, 2.8], [0.0, 3.7], [-2.8, 2.8]])
#: the hand padded far more than the rest, so that every shape's own padding counts in what a search proves
PADDING = {link: 0.25 if link == "panda_hand" else 0.01 for link in KIN.links}


def clutter(rng: np.random.Generator, n: int, low: tuple[float, float], high: tuple[float, float],
            mass: float = 0.0) -> list[Obstacle]:
    """``n`` small boxes and cylinders, footprints uniform over the rectangle ``low``..``high``."""
    out = []
    for _ in range(n):
        sx, sy, sz = rng.uniform(0.02, 0.3, size=3)
        position = tuple(float(v) for v in rng.uniform(low, high))
        z = float(rng.uniform(0.0, 0.6))
        if rng.random() < 0.4:
            out.append(Obstacle("cylinder", (sx, sx, sz), position, 0.0, z, mass))
        else:
            out.append(Obstacle("box", (sx, sy, sz), position, float(rng.uniform(-np.pi, np.pi)), z, mass))
    return out


def walls(half: float) -> list[Obstacle]:
    """Four thin walls about the origin: outsized obstacles, which the k-d tree leaves to be checked one by one."""
    return [Obstacle("box", (2 * half, 0.05, 1.0), (0.0, y)) for y in (-half, half)] + [
        Obstacle("box", (0.05, 2 * half, 1.0), (x, 0.0)) for x in (-half, half)]


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


def arm_state(q: np.ndarray, offset: np.ndarray, yaw: float = 0.0) -> RobotState:
    """The Panda at joint angles ``q``, its base at ``offset`` turned by ``yaw``."""
    frames = KIN.forward(np.concatenate([q, FINGERS])[None])
    turn = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    position = np.stack([frames[n][0, :3, 3] for n in KIN.links]) @ turn.T + offset
    rotation = turn @ np.stack([frames[n][0, :3, :3] for n in KIN.links])
    zeros = np.zeros((len(KIN.links) - 1, 3))
    links = LinkStates(position[1:], rotation[1:], zeros, zeros)
    return RobotState(position[0], rotation[0], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), links, tuple(KIN.links[1:]), {}, -1)


# ---------------------------------------------------------------------------------------------- the k-d tree
def every_column(bounds: ObstacleBounds, centre: np.ndarray, reach: float) -> np.ndarray:
    """What :meth:`ObstacleBounds.near` answered before its k-d tree: a pass over every column."""
    return np.flatnonzero(np.linalg.norm(bounds.centres - centre, axis=1) - bounds.enclosing <= reach)


def test_tree_near_equals_a_pass_over_every_column_with_walls_and_moved_obstacles():
    """Random scenes with walls and movable obstacles, some moved before the tree is built and some after (far
    across the scene, and tipped over): every answer equals the pass over every column, including the answers that
    hold a moved obstacle far from where the tree has it, and the walls."""
    rng = np.random.default_rng(0)
    moved_far = walls_kept = 0
    for scene in range(6):
        obstacles = clutter(rng, 300, (-6.0, -6.0), (6.0, 6.0), mass=1.0) + walls(7.0)
        bounds = ObstacleBounds(obstacles)
        if scene % 2:  # moves before the first query land in the tree
            early = rng.choice(300, 20, replace=False)
            bounds.move(early, rng.uniform(-6.0, 6.0, (20, 3)), np.array([random_rotation(rng) for _ in early]))
        built = bounds.centres.copy()  # where the tree, built on the first query, holds them
        for _ in range(4):
            for _ in range(40):
                centre, reach = rng.uniform(-7.5, 7.5, 3), float(rng.choice([-0.2, 0.0, 0.3, 1.0, 3.0]))
                got = bounds.near(centre, reach)
                np.testing.assert_array_equal(got, every_column(bounds, centre, reach))
                # columns the answer holds whose centre in the tree lies beyond the tree's search
                old_gap = np.linalg.norm(built[got] - centre, axis=1) - bounds.enclosing[got]
                moved_far += int((old_gap > reach + 0.5).sum())
                walls_kept += int(np.isin(bounds.index[got], np.arange(300, 304)).sum())
            k = int(rng.integers(5, 30))
            moved = rng.choice(300, k, replace=False)
            bounds.move(moved, rng.uniform(-6.0, 6.0, (k, 3)), np.array([random_rotation(rng) for _ in moved]))
    assert moved_far > 20 and walls_kept > 20, (moved_far, walls_kept)


# ---------------------------------------------------------------------------------- narrow first, or every obstacle
def checker_pair(fidelity: str, per_link: bool, obstacles: list[Obstacle], clearance_range: float = 12.0,
                 swept_speed: float = np.inf) -> tuple[CollisionChecker, CollisionChecker]:
    """Two checkers of one robot and scene: one to search narrow first, one to be asked with ``SMALL_SCENE`` out of
    the way (every obstacle bounded, :func:`every_obstacle`)."""
    out = []
    for _ in range(2):
        model = RobotCollisionModel.from_urdf(URDF, fidelity, KIN.links, padding=PADDING)
        checker = CollisionChecker(model, "panda_link0", contact_tolerance=0.005, clearance_range=clearance_range,
                                   swept_speed=swept_speed, per_link=per_link)
        checker.set_scene(obstacles, [])
        out.append(checker)
    return out[0], out[1]


def every_obstacle(monkeypatch, call):
    """``call()`` with every obstacle bounded, as in a scene of at most ``SMALL_SCENE`` obstacles."""
    with monkeypatch.context() as m:
        m.setattr(nearest_module, "SMALL_SCENE", 10**9)
        return call()


def assert_same_report(got, expected) -> None:
    assert got.min_clearance == expected.min_clearance
    assert got.closest == expected.closest
    np.testing.assert_array_equal(got.witness, expected.witness)
    np.testing.assert_array_equal(got.link_clearance, expected.link_clearance)
    np.testing.assert_array_equal(got.directions, expected.directions)
    assert [(c.link, c.obstacle, c.depth) for c in got.contacts] == [
        (c.link, c.obstacle, c.depth) for c in expected.contacts]
    for a, b in zip(got.contacts, expected.contacts):
        np.testing.assert_array_equal(a.position, b.position)
    assert got.self_collision == expected.self_collision
    assert got.tunneling == expected.tunneling


def compare(monkeypatch, narrow: CollisionChecker, full: CollisionChecker, state: RobotState, seen: dict) -> None:
    """Check ``state`` with both checkers, and (per link) every shape's clearance, obstacle and witness points."""
    got, expected = narrow.check(state), every_obstacle(monkeypatch, lambda: full.check(state))
    assert_same_report(got, expected)
    if narrow.per_link:
        for a, b in zip(narrow.clearance(), every_obstacle(monkeypatch, full.clearance)):
            np.testing.assert_array_equal(a, b)
    seen["in range"] += got.closest is not None
    seen["contacts"] += got.in_contact
    seen["tunneling"] += got.tunneling


@pytest.mark.parametrize("per_link", [True, False])
@pytest.mark.parametrize("fidelity", ["primitive", "sphere"])
def test_narrow_first_search_equals_every_obstacle_on_random_poses(monkeypatch, fidelity, per_link):
    """Random arm poses among dense clutter (contacts), in a sparse scene (widened searches), with nothing within
    the first search, and next to a lone obstacle far from the rest: every answer is the one every obstacle gives."""
    rng = np.random.default_rng(11 + per_link)
    dense = clutter(rng, 400, (-2.5, -2.5), (2.5, 2.5)) + walls(11.0)
    medium = clutter(rng, 250, (-8.0, -8.0), (8.0, 8.0))  # nearest obstacles about as far as the first search
    lone = Obstacle("box", (0.1, 0.3, 0.4), (9.0, 9.0), 0.3, 0.2)
    sparse = clutter(rng, 200, (-10.0, -10.0), (10.0, -4.0)) + [lone] + walls(11.0)
    assert min(len(dense), len(sparse)) > SMALL_SCENE
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}
    for obstacles, offsets in ((dense, rng.uniform(-2.0, 2.0, (25, 2))), (medium, rng.uniform(-7.0, 7.0, (100, 2))),
                               (sparse, np.concatenate([rng.uniform(-10.0, 10.0, (20, 2)),
                                                        [[0.0, 4.0], [9.0, 8.2], [8.3, 9.0]]]))):
        narrow, full = checker_pair(fidelity, per_link, obstacles)
        for x, y in offsets:
            state = arm_state(rng.uniform(LIMITS[:, 0], LIMITS[:, 1]), np.array([x, y, 0.0]),
                              float(rng.uniform(-np.pi, np.pi)))
            compare(monkeypatch, narrow, full, state, seen)
    assert seen["in range"] == 148 and seen["contacts"] > 5, seen


@pytest.mark.parametrize("per_link", [True, False])
@pytest.mark.parametrize("fidelity", ["primitive", "sphere"])
def test_an_arm_beside_dense_clutter_widens_onto_many_obstacles(monkeypatch, fidelity, per_link):
    """The arm beside a dense patch of clutter: shapes far from it find nothing in the first search, and the wider
    one finds far more obstacles than ``SMALL_SCENE``, of which some shapes keep few and some many; every answer
    is the one every obstacle gives."""
    rng = np.random.default_rng(1)
    obstacles = [Obstacle("box", (0.08, 0.08, 0.08), (float(x), float(y)), 0.0, float(z))
                 for x, y, z in rng.uniform((0.8, -1.5, 0.0), (2.5, 1.5, 1.2), (600, 3))]
    narrow, full = checker_pair(fidelity, per_link, obstacles)
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}
    for _ in range(15):
        state = arm_state(rng.uniform(LIMITS[:, 0], LIMITS[:, 1]), np.zeros(3), float(rng.uniform(-np.pi, np.pi)))
        compare(monkeypatch, narrow, full, state, seen)
    assert seen["in range"] == 15 and seen["contacts"] > 0, seen


# ------------------------------------------------------------------------------ the edge of the first search
def one_link_robot(path, geometry: str) -> RobotCollisionModel:
    """A robot that is one link "body" of the URDF collision ``geometry`` (elements centred on its origin), padded
    by ``EDGE_PADDING``."""
    path.write_text(f'<robot name="r"><link name="base"/><link name="body">{geometry}</link><joint name="j" '
                    'type="floating"><parent link="base"/><child link="body"/></joint></robot>')
    shapes = build_link_shapes(load_collision_elements(path), "primitive")
    return RobotCollisionModel(shapes, ("base", "body"), EDGE_PADDING)


def body_state(position: np.ndarray) -> RobotState:
    links = LinkStates(position[None], np.eye(3)[None], np.zeros((1, 3)), np.zeros((1, 3)))
    return RobotState(np.zeros(3), np.eye(3), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), links, ("body",), {}, -1)


EDGE_PADDING = 0.1
#: how far inside or outside the first search the obstacles of :func:`test_the_first_search_is_exact_at_its_edge`
#: are put, metres
EDGE = 0.02
#: (URDF collision elements, distance from the origin to the surface along +x, enclosing radius): a cube (FCL
#: measures it: its bounds are loose) and eight concentric spheres (a sphere set: its bounds are its distances)
EDGE_ROBOTS = {
    "cube": ('<collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>', 0.1, 0.1 * np.sqrt(3.0)),
    "sphere-set": ("".join(f'<collision><geometry><sphere radius="{r}"/></geometry></collision>'
                           for r in (0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.095, 0.1)), 0.1, 0.1),
}


def corner_on_cube(point: np.ndarray, gap: float, side: float = 0.1) -> Obstacle:
    """An upright cube below and behind ``point`` (towards -x, -y, -z), its corner ``gap`` from ``point`` on the
    diagonal through it: its enclosing ball comes exactly as near as its corner, so it is as near as the search's
    proof lets an obstacle it leaves out be, and near a robot's corner on that diagonal too."""
    centre = point - (gap + 0.5 * side * np.sqrt(3.0)) * np.ones(3) / np.sqrt(3.0)
    return Obstacle("box", (side, side, side), (float(centre[0]), float(centre[1])), 0.0, float(centre[2] - side / 2))


def broadside_slat(point: np.ndarray, gap: float, length: float = 1.0) -> Obstacle:
    """A long thin slat along y, its face ``gap`` from ``point`` towards +x: its enclosing ball comes far nearer
    than its face, so every search keeps it."""
    return Obstacle("box", (0.02, length, 0.04), (float(point[0] + gap + 0.01), float(point[1])), 0.0,
                    float(point[2] - 0.02))


@pytest.mark.parametrize("per_link", [True, False])
@pytest.mark.parametrize("robot", EDGE_ROBOTS)
def test_the_first_search_is_exact_at_its_edge(monkeypatch, tmp_path, robot, per_link):
    """A one-link robot (a cube FCL measures, or a sphere set answered from its bounds) where the first search's
    answer is right only by ``EDGE``: a cube just inside the search and a slat just farther (a search that reaches
    too short, or leaves out the padding or the obstacles' size, answers the slat), and a cube just outside the
    search and a slat just beyond it, bounded within it (a proof too loose to widen answers the slat)."""
    geometry, face, enclosing = EDGE_ROBOTS[robot]
    reach = enclosing + EDGE_PADDING  # the one ball about the robot's middle, padded
    inside, outside = np.array([0.0, 0.0, 1.0]), np.array([5.0, 0.0, 1.0])
    obstacles = [corner_on_cube(inside, reach + FIRST_SEARCH - EDGE),
                 broadside_slat(inside, face + EDGE_PADDING + FIRST_SEARCH - EDGE / 2),
                 corner_on_cube(outside, reach + FIRST_SEARCH + EDGE),
                 broadside_slat(outside, face + EDGE_PADDING + FIRST_SEARCH + 2 * EDGE)]
    obstacles += clutter(np.random.default_rng(5), 200, (-10.0, 4.0), (10.0, 10.0))  # far off: a large scene
    out = []
    for _ in range(2):
        checker = CollisionChecker(one_link_robot(tmp_path / "robot.urdf", geometry), "base", contact_tolerance=0.005,
                                   clearance_range=8.0, swept_speed=np.inf, per_link=per_link)
        checker.set_scene(obstacles, [])
        out.append(checker)
    narrow, full = out
    assert narrow.model.lazy.all() == (robot == "sphere-set")
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}
    for point, cube, gap in ((inside, 0, -EDGE), (outside, 2, EDGE)):
        compare(monkeypatch, narrow, full, body_state(point), seen)
        report = narrow.check(body_state(point))
        assert report.closest == ("body", cube)
        assert report.min_clearance == pytest.approx(FIRST_SEARCH + gap, abs=1e-6)


@pytest.mark.parametrize("per_link", [True, False])
def test_a_pose_with_nothing_near_widens_and_one_by_a_lone_pillar_stays_narrow(monkeypatch, per_link):
    """The two poses the first search cannot or can settle alone: nothing within it (the answer is metres off,
    found by widening, and must be what every obstacle gives), and an upright arm beside a lone pillar far from
    the rest (every shape answered by the first search)."""
    rng = np.random.default_rng(4)
    pillar = Obstacle("box", (0.2, 0.2, 1.3), (9.0, 9.0))
    obstacles = clutter(rng, 200, (-10.0, -10.0), (10.0, -4.0)) + [pillar]
    narrow, full = checker_pair("primitive", per_link, obstacles)
    searches = []
    lower_bounds = narrow.search.lower_bounds
    narrow.search.lower_bounds = lambda grow=None, within=None: (searches.append(within), lower_bounds(grow, within))[1]
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}
    alone = arm_state(np.zeros(7), np.array([0.0, 3.0, 0.0]))
    compare(monkeypatch, narrow, full, alone, seen)
    assert max(searches) > 4.0 * FIRST_SEARCH and seen["in range"] == 1
    searches.clear()
    beside = arm_state(np.zeros(7), np.array([9.0, 8.55, 0.0]), np.pi)
    compare(monkeypatch, narrow, full, beside, seen)
    assert set(searches) == {FIRST_SEARCH}
    assert narrow.check(beside).closest[1] == len(obstacles) - 1


def test_obstacles_left_out_of_a_narrow_search_are_bounded_beyond_it():
    """What each narrow search proves: every obstacle it leaves out has, for every shape, a bound (every obstacle
    bounded) above the search's ``within`` plus the shape's padding."""
    rng = np.random.default_rng(2)
    obstacles = clutter(rng, 300, (-4.0, -4.0), (4.0, 4.0))
    narrow, _ = checker_pair("primitive", True, obstacles)
    padding = narrow.model.padding[narrow.search.moving][:, None]
    left_out = 0
    for _ in range(30):
        narrow.sync(arm_state(rng.uniform(LIMITS[:, 0], LIMITS[:, 1]), np.append(rng.uniform(-4.0, 4.0, 2), 0.0)))
        search = narrow.search
        every = search.bounds.signed_distance(narrow.model.ball_centres()[search.moving]) - search.slack_radii
        for within in narrow.search.search_radii()[:-1]:
            candidates, _ = narrow.search.lower_bounds(within=within)
            out = np.setdiff1d(np.arange(len(obstacles)), candidates)
            columns = narrow.search.bounds._column[out]
            assert (every[:, columns] - padding > within).all()
            left_out += out.size
    assert left_out > 1000


# ------------------------------------------------------------------------------------ motion, and the envs
@pytest.mark.parametrize("per_link", [True, False])
def test_contacts_and_swept_hits_equal_every_obstacle_on_a_fast_motion(monkeypatch, per_link):
    """The arm carried fast (up to 0.9 m a step, farther than the first search) and swinging through a field of
    thin walls and movable clutter that moves between steps: contacts and swept hits are those every obstacle
    gives."""
    rng = np.random.default_rng(7 + per_link)
    fins = [Obstacle("box", (0.01, 0.6, 0.8), (float(x), float(y)), float(rng.uniform(-0.3, 0.3)))
            for x in np.arange(-3.0, 3.01, 0.5) for y in (-1.0, 0.0, 1.0)]
    movable = clutter(rng, 60, (-3.0, -1.5), (3.0, 1.5), mass=1.0)
    obstacles = fins + clutter(rng, 120, (-3.0, -1.5), (3.0, 1.5)) + movable
    narrow, full = checker_pair("primitive", per_link, obstacles, clearance_range=6.0, swept_speed=0.2)
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}
    q = rng.uniform(LIMITS[:, 0], LIMITS[:, 1])
    moved = np.arange(len(obstacles) - len(movable), len(obstacles))
    for step in range(60):
        x = -3.2 + 0.1 * step + (0.8 * (step % 2))  # back and forth: 0.9 m, then 0.7 m back
        q = q + rng.uniform(-0.6, 0.6, 7)
        if step % 5 == 4:
            centres = np.column_stack([rng.uniform(-3.0, 3.0, (len(moved), 2)), rng.uniform(0.0, 0.6, len(moved))])
            rotations = np.array([random_rotation(rng) for _ in moved])
            narrow.move_obstacles(moved, centres, rotations)
            full.move_obstacles(moved, centres, rotations)
        compare(monkeypatch, narrow, full, arm_state(np.clip(q, LIMITS[:, 0], LIMITS[:, 1]),
                                                     np.array([x, float(rng.uniform(-1.2, 1.2)), 0.0])), seen)
    assert seen["contacts"] > 5 and seen["tunneling"] > 5, seen


def checked_both_ways(checker: CollisionChecker, monkeypatch, seen: dict):
    """A stand-in for ``checker.check`` that checks each state with every obstacle bounded first, then as the
    checker does, and asserts the two reports are the same (the checker's memory of the last check is put back
    in between, so that both see the same previous step)."""
    check = checker.check

    def compared(state, pybullet_contacts=()):
        before = checker.audit.previous, checker._touching
        expected = every_obstacle(monkeypatch, lambda: check(state, pybullet_contacts))
        checker.audit.previous, checker._touching = before
        got = check(state, pybullet_contacts)
        assert_same_report(got, expected)
        seen["in range"] += got.closest is not None
        seen["contacts"] += got.in_contact
        seen["tunneling"] += got.tunneling
        return got

    return compared


def test_clutterfly_in_a_large_volume_reports_what_every_obstacle_gives(make_env, monkeypatch):
    """ClutterFly-v1 measures only the robot's nearest pair: along random flights through a volume of some 400
    obstacles (crashes included), every report is the one every obstacle bounded gives."""
    env = make_env("ClutterFly-v1", volume_size=(12.0, 12.0, 3.0), obstacle_density=0.25)
    checker = env.unwrapped.checker
    assert not checker.per_link
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}
    checker.check = checked_both_ways(checker, monkeypatch, seen)
    rng = np.random.default_rng(2)
    env.reset(seed=2)
    assert len(checker.search.bounds) > SMALL_SCENE
    for _ in range(250):
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, 4))
        if terminated or truncated:
            env.reset()
    assert seen["in range"] > 50 and seen["contacts"] > 0, seen
