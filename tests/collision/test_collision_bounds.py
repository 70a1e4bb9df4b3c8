"""Bounds first, FCL only where it can matter: the closed-form bounds are lower bounds, and pruning with them
changes no result (clearance, witnesses, contacts, self-collision) against brute force over every pair."""

from __future__ import annotations

import fcl
import numpy as np
import pytest

from clutter_gym.collision import CollisionChecker, RobotCollisionModel, UrdfKinematics
from clutter_gym.collision.bounds import ObstacleBounds
from clutter_gym.collision.distance import signed_distance
from clutter_gym.collision.nearest import SMALL_SCENE
from clutter_gym.collision.obstacles import obstacle_object
from clutter_gym.datatypes import Obstacle
from clutter_gym.robots import PandaArm

URDF = PandaArm().urdf_path
KIN = UrdfKinematics(URDF)
FINGERS = [0.02, 0.02]


def random_obstacles(rng: np.random.Generator, n: int, spread: float = 0.8) -> list[Obstacle]:
    out = []
    for _ in range(n):
        sx, sy, sz = rng.uniform(0.03, 0.4, size=3)
        position = tuple(rng.uniform(-spread, spread, size=2))
        if rng.random() < 0.4:
            out.append(Obstacle("cylinder", (sx, sx, sz), position, 0.0, float(rng.uniform(0.0, 0.5))))
        else:
            out.append(Obstacle("box", (sx, sy, sz), position, float(rng.uniform(-np.pi, np.pi)),
                                float(rng.uniform(0.0, 0.5))))
    return out


def placed(geometry: fcl.CollisionGeometry, position: np.ndarray, rotation: np.ndarray) -> fcl.CollisionObject:
    return fcl.CollisionObject(geometry, fcl.Transform(rotation, position))


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r)) * np.linalg.det(q * np.sign(np.diag(r)))


# ---------------------------------------------------------------------------------------------- bounds
def test_point_distance_matches_closed_forms():
    box = Obstacle("box", (0.4, 0.2, 0.6), (1.0, 2.0), np.pi / 2, 0.1)  # footprint turned: 0.2 along x
    cylinder = Obstacle("cylinder", (0.2, 0.2, 0.5), (0.0, 0.0), 0.0, 0.0)
    bounds = ObstacleBounds([cylinder, box])
    assert list(bounds.index) == [1, 0]  # boxes first
    points = np.array([
        [1.0, 2.0, 0.4],    # box centre: 0.1 inside to the nearest face (x after the turn)
        [1.5, 2.0, 0.4],    # 0.4 beyond the box's x face
        [1.3, 2.5, 0.9],    # past an edge corner: (0.2, 0.3, 0.2) out
        [0.0, 0.0, 0.25],   # cylinder centre: 0.1 from the side, 0.25 from the caps
        [0.3, 0.4, 0.25],   # 0.4 off the side
        [0.3, 0.4, 0.8],    # off the rim: 0.4 radially, 0.3 above
    ])
    d = bounds.signed_distance(points)
    np.testing.assert_allclose(d[:3, 0], [-0.1, 0.4, np.sqrt(0.2**2 + 0.3**2 + 0.2**2)], atol=1e-12)
    np.testing.assert_allclose(d[3:, 1], [-0.1, 0.4, 0.5], atol=1e-12)
    np.testing.assert_allclose(bounds.signed_distance(points, np.array([1])), d[:, 1:], atol=0)


def test_ball_bounds_are_lower_bounds_of_fcl_distances_on_both_sides_of_contact():
    """Random boxes, capsules and spheres inside their balls, against random obstacles; over a hundred pairs
    overlap. For a sphere the bound is its exact distance."""
    rng = np.random.default_rng(0)
    checked = overlapping = 0
    for _ in range(60):
        obstacles = random_obstacles(rng, 6, spread=0.3)
        bounds = ObstacleBounds(obstacles)
        objects = [obstacle_object(obstacles[j]) for j in bounds.index]
        for _ in range(10):
            centre, rotation = rng.uniform(-0.5, 0.7, size=3), random_rotation(rng)
            kind = rng.integers(3)
            if kind == 0:
                radius = float(rng.uniform(0.02, 0.2))
                geometry = fcl.Sphere(radius)
            elif kind == 1:
                r, length = rng.uniform(0.02, 0.1), rng.uniform(0.0, 0.3)
                geometry, radius = fcl.Capsule(r, length), r + 0.5 * length
            else:
                half = rng.uniform(0.01, 0.15, size=3)
                geometry, radius = fcl.Box(*(2 * half)), float(np.linalg.norm(half))
            shape = placed(geometry, centre, rotation)
            lower = bounds.signed_distance(centre[None])[0] - radius
            for b, obstacle in zip(lower, objects):
                d, _ = signed_distance(shape, obstacle)
                # EPA's depth and GJK's distance carry about 1e-6 m of error; a bound is useful far above that
                assert b <= d + 1e-5
                if kind == 0 and d > 1e-3:
                    assert b == pytest.approx(d, abs=1e-5)
                checked += 1
                overlapping += d <= 0.0
    assert checked == 3600 and overlapping > 100


# ---------------------------------------------------------------------------- pruning changes nothing
def brute_force(checker: CollisionChecker, obstacles: list[Obstacle]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every moving shape against every obstacle, nearest kept: what :meth:`CollisionChecker.clearance` means."""
    model, objects = checker.model, [obstacle_object(o) for o in obstacles]
    n = len(model.objects)
    best, other, points = np.full(n, checker.clearance_range), np.full(n, -1), np.zeros((n, 2, 3))
    for i in checker.search.moving:
        for j, obstacle in enumerate(objects):
            d, result = signed_distance(model.object(i), obstacle, model.solid_object(i))
            if d - model.padding[i] < best[i]:
                best[i], other[i], points[i] = d - model.padding[i], j, result.nearest_points
    return best, other, points


def panda_state(q: np.ndarray):
    frames = KIN.forward(np.concatenate([q, FINGERS])[None])
    return (np.stack([frames[n][0, :3, 3] for n in KIN.links]), np.stack([frames[n][0, :3, :3] for n in KIN.links]))


@pytest.mark.parametrize("fidelity", ["primitive", "mesh"])
@pytest.mark.parametrize("n_obstacles", [12, SMALL_SCENE + 40])
def test_pruned_clearance_equals_brute_force_on_random_panda_poses(fidelity, n_obstacles):
    rng = np.random.default_rng(n_obstacles)
    model = RobotCollisionModel.from_urdf(URDF, fidelity, KIN.links, padding=0.01)
    checker = CollisionChecker(model, "panda_link0", clearance_range=0.3, fixed_links=("panda_link0",))
    limits = np.array([[-2.8, 2.8], [-1.7, 1.7], [-2.8, 2.8], [-3.0, -0.1], [-2.8, 2.8], [0.0, 3.7], [-2.8, 2.8]])
    near = 0
    for _ in range(15):
        obstacles = random_obstacles(rng, n_obstacles, spread=0.8 if n_obstacles < SMALL_SCENE else 2.0)
        checker.set_scene(obstacles, [])
        for _ in range(4):
            model.sync(*panda_state(rng.uniform(limits[:, 0], limits[:, 1])))
            got, expected = checker.clearance(), brute_force(checker, obstacles)
            for g, e in zip(got, expected):
                np.testing.assert_array_equal(g, e)
            near += int((expected[1] >= 0).sum())
    assert near > 100  # most poses have links within range of something


@pytest.mark.parametrize("fidelity", ["sphere", "spheres"])
def test_sphere_distances_come_from_their_bounds_and_equal_fcl(fidelity):
    """Spheres make no FCL distance call: their ball bound is their distance. It must equal FCL's wherever FCL is
    exact (separated spheres against boxes and cylinders), and the witness points a link reports must be FCL's."""
    rng = np.random.default_rng(5)
    model = RobotCollisionModel.from_urdf(URDF, fidelity, KIN.links, padding=0.01)
    checker = CollisionChecker(model, "panda_link0", clearance_range=0.3, fixed_links=("panda_link0",))
    assert model.lazy[checker.search.moving].all()  # a sphere set: answered from the bounds
    limits = np.array([[-2.8, 2.8], [-1.7, 1.7], [-2.8, 2.8], [-3.0, -0.1], [-2.8, 2.8], [0.0, 3.7], [-2.8, 2.8]])
    compared = 0
    for _ in range(10):
        obstacles = random_obstacles(rng, 12, spread=0.8)
        checker.set_scene(obstacles, [])
        for _ in range(4):
            model.sync(*panda_state(rng.uniform(limits[:, 0], limits[:, 1])))
            (got, got_other, got_points), (expected, other, points) = checker.clearance(), brute_force(checker,
                                                                                                          obstacles)
            separated = expected > 0.0
            np.testing.assert_allclose(got[separated], expected[separated], rtol=0, atol=1e-12)
            np.testing.assert_array_equal(got_other[separated], other[separated])
            for shapes in checker.search.link_shapes:  # the shape each link reports carries FCL's witness points
                i = shapes[int(np.argmin(got[shapes]))]
                if got_other[i] >= 0 and separated[i]:
                    np.testing.assert_allclose(got_points[i], points[i], rtol=0, atol=1e-9)
                    compared += 1
    assert compared > 50


def test_pruned_self_collision_equals_every_pair():
    model = RobotCollisionModel.from_urdf(URDF, "convex", KIN.links, padding=0.005)
    rng = np.random.default_rng(3)
    hits = 0
    for _ in range(150):
        model.sync(*panda_state(rng.uniform(-3.0, 3.0, size=7)))
        distances = [model._pair_distance(i, j) for i, j in model.self_pairs]
        k = int(np.argmin(distances))
        clearance = model.self_clearance()
        assert clearance.distance == distances[k]
        assert clearance.links == (model.shapes[model.self_pairs[k][0]].link, model.shapes[model.self_pairs[k][1]].link)
        first = next(((model.shapes[i].link, model.shapes[j].link) for (i, j), d in zip(model.self_pairs, distances)
                      if d <= 0.0), None)
        assert model.self_collision() == first
        hits += first is not None
    assert 20 < hits < 150


@pytest.mark.parametrize("fidelity", ["primitive", "convex", "mesh"])
def test_enclosing_balls_hold_every_vertex(fidelity):
    """The balls the bounds use contain each shape (its mesh vertices, or the primitive's extreme points)."""
    from clutter_gym.collision import build_link_shapes, load_collision_elements

    elements = load_collision_elements(URDF)
    for element, shape in zip(elements, build_link_shapes(elements, fidelity)):
        centre, radius = shape.bounding_ball
        if fidelity == "primitive":
            assert radius == shape.radius and not centre.any()
            continue
        vertices = np.asarray(element.mesh.vertices)
        assert np.linalg.norm(vertices - centre, axis=1).max() <= radius + 1e-12
        assert radius <= shape.radius  # never looser than the ball about the origin


def test_moved_obstacles_keep_exact_point_distances_at_any_orientation():
    """Movable obstacles can be tipped over: after ``move`` the closed forms still give FCL's point distances."""
    rng = np.random.default_rng(7)
    obstacles = random_obstacles(rng, 12)
    bounds = ObstacleBounds(obstacles)
    moved = np.array([1, 4, 5, 9])
    centres = rng.uniform(-0.5, 0.5, size=(len(moved), 3))
    rotations = np.array([random_rotation(rng) for _ in moved])
    bounds.move(moved, centres, rotations)
    points = rng.uniform(-1.0, 1.0, size=(40, 3))
    d = bounds.signed_distance(points)
    for column, j in enumerate(bounds.index):
        o = obstacle_object(obstacles[j])
        if j in moved:
            k = int(np.flatnonzero(moved == j)[0])
            o.setTransform(fcl.Transform(rotations[k], centres[k]))
        for p, expected in zip(points, d[:, column]):
            point = placed(fcl.Sphere(1e-9), p, np.eye(3))
            exact, _ = signed_distance(point, o)
            if exact > 1e-6:  # outside: FCL's distance is exact; inside, FCL's depth is the same closed form's
                assert expected == pytest.approx(exact, abs=1e-6)
            else:
                assert expected <= 1e-6


# ------------------------------------------------------------------------ the nearest pair alone (per_link=False)
@pytest.mark.parametrize("fidelity, padding", [("primitive", 0.0), ("mesh", 0.01), ("spheres", 0.005)])
def test_nearest_pair_checker_reports_what_the_per_link_checker_does(make_env, fidelity, padding):
    """ClutterFly-v1 measures only the robot's nearest pair. Along random-action flights through generated volumes
    (crashes into the floor and the clutter included), a per-link checker of the same model, given the same scenes
    and states, must report the same clearance, nearest pair, witness points, contacts and swept hits."""
    env = make_env("ClutterFly-v1", volume_size=(6.0, 6.0, 3.0), obstacle_density=0.15,
                   collision_fidelity=fidelity, collision_padding=padding)
    checker = env.unwrapped.checker
    assert not checker.per_link
    reference = CollisionChecker(
        RobotCollisionModel(checker.model.shapes, checker.model.link_names, padding), checker._base_link,
        contact_tolerance=checker.contact_tolerance, clearance_range=checker.clearance_range,
        swept_speed=checker.swept_speed, dt=checker.dt)
    set_scene, check = checker.set_scene, checker.check
    checker.set_scene = lambda obstacles, bodies: (reference.set_scene(obstacles, bodies), set_scene(obstacles, bodies))
    seen = {"in range": 0, "contacts": 0, "tunneling": 0}

    def compared(state, pybullet_contacts=()):
        got, expected = check(state, pybullet_contacts), reference.check(state, pybullet_contacts)
        assert got.min_clearance == expected.min_clearance
        assert got.closest == expected.closest
        np.testing.assert_array_equal(got.witness, expected.witness)
        assert [(c.link, c.obstacle, c.depth) for c in got.contacts] == [
            (c.link, c.obstacle, c.depth) for c in expected.contacts]
        for a, b in zip(got.contacts, expected.contacts):
            np.testing.assert_array_equal(a.position, b.position)
        assert got.tunneling == expected.tunneling
        assert got.link_clearance is None and got.directions is None
        seen["in range"] += got.closest is not None
        seen["contacts"] += got.in_contact
        seen["tunneling"] += got.tunneling > 0
        return got

    checker.check = compared
    rng = np.random.default_rng(3)
    env.reset(seed=3)
    for _ in range(600):
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, 4))
        if terminated or truncated:
            env.reset()
    assert seen["in range"] > 300 and seen["contacts"] > 3, seen
