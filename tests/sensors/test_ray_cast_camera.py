"""The ray-cast depth camera (Sim.ray_cast_image, camera_renderer="rays"): depths against closed forms for a box
face, a cylinder, the ground and the near and far planes; the shape table following the Sim's bodies; agreement
with TinyRenderer on generated ClutterFly-v1 scenes; the env boundary."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy import ndimage

from clutter_gym.sensors.camera import _view_matrix
from clutter_gym.sim import Sim
from clutter_gym.sim.ray_casting import BOX

#: forward +x, right -y, down -z: a camera at the origin looking along +x, level
LEVEL = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
SIZE = 41  # odd: the middle row and column look along the optical axis's planes
FOV = math.radians(60.0)
F = (SIZE / 2) / math.tan(FOV / 2)
INTRINSICS = (F, F, (SIZE - 1) / 2, (SIZE - 1) / 2)
U = (np.arange(SIZE) - (SIZE - 1) / 2) / F  # normalised image coordinate of each column (and row)


def cast(sim: Sim, eye=(0.0, 0.0, 0.0), near: float = 0.05, far: float = 10.0):
    return sim.rendering.ray_cast_image(SIZE, SIZE, np.array(eye, dtype=float), LEVEL, INTRINSICS, near, far)


@pytest.fixture
def sim():
    s = Sim(visuals=False)  # the ray caster needs no visual shapes
    yield s
    s.close()


def test_a_box_face_reads_its_distance(sim):
    """A face 3 m ahead, 2 m square: every pixel whose ray meets it reads 3 m exactly, every other pixel 0."""
    (box,) = sim.obstacles.add_static_boxes((0.1, 1.0, 1.0), (0.5, 0.5, 0.5, 1.0), [(3.1, 0.0, 0.0)])
    depth, ids = cast(sim)
    inside = (np.abs(U[:, None]) * 3.0 < 1.0) & (np.abs(U[None, :]) * 3.0 < 1.0)
    np.testing.assert_array_equal(depth[inside], 3.0)
    np.testing.assert_array_equal(depth[~inside], 0.0)
    np.testing.assert_array_equal(ids, np.where(inside, box, -1))


def test_a_cylinder_along_the_middle_row(sim):
    """An upright cylinder of radius r, d ahead: along the level middle row the ray (1, -u, 0) meets the circle at
    t = (d - sqrt(d^2 - (1 + u^2)(d^2 - r^2))) / (1 + u^2); past the tangent rays nothing."""
    d, r = 4.0, 0.5
    sim.obstacles.add_static_cylinders(r, 2.0, (0.5, 0.5, 0.5, 1.0), [(d, 0.0, 0.0)])
    depth, _ = cast(sim)
    row = depth[SIZE // 2]
    disc = d * d - (1 + U**2) * (d * d - r * r)
    hit = disc >= 0
    expected = (d - np.sqrt(np.where(hit, disc, 0.0))) / (1 + U**2)
    assert 5 < hit.sum() < SIZE
    np.testing.assert_allclose(row[hit], expected[hit], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(row[~hit], 0.0)


def test_a_cylinder_cap_from_above(sim):
    """Looking straight down at an upright cylinder's top, h below the eye: the pixels whose ray meets the top's
    plane within the radius read h, the others nothing (their rays diverge from the side)."""
    h, r = 2.0, 0.6
    sim.obstacles.add_static_cylinders(r, 1.0, (0.5, 0.5, 0.5, 1.0), [(0.0, 0.0, -h - 0.5)])
    down = np.array([[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]])  # forward -z, right -y, down -x
    depth, _ = sim.rendering.ray_cast_image(SIZE, SIZE, np.zeros(3), down, INTRINSICS, 0.05, 10.0)
    inside = np.hypot(U[:, None], U[None, :]) * h <= r
    assert inside.sum() > 50
    np.testing.assert_array_equal(depth[inside], h)
    np.testing.assert_array_equal(depth[~inside], 0.0)


def test_the_ground_from_a_level_camera(sim):
    """A level camera h above the ground: a row v below the middle meets it at depth h / v, rows at and above the
    horizon see nothing; the drawn square (20 m) ends the floor."""
    h = 1.5
    sim.add_ground(20.0)
    depth, _ = cast(sim, eye=(0.0, 0.0, h), far=50.0)
    rows = U > 0
    expected = np.broadcast_to((h / np.where(rows, U, 1.0))[:, None], depth.shape)
    on_square = rows[:, None] & (expected < 10.0) & (np.abs(U[None, :] * expected) < 10.0)
    np.testing.assert_allclose(depth[on_square], expected[on_square], rtol=1e-12)
    np.testing.assert_array_equal(depth[~rows], 0.0)


def test_near_and_far_planes(sim):
    """A box cut by the near plane shows its far face from inside (as a rasteriser without back-face culling
    does); a surface at or beyond the far plane is not seen."""
    sim.obstacles.add_static_boxes((0.24, 5.0, 5.0), (0.5, 0.5, 0.5, 1.0), [(0.26, 0.0, 0.0)])  # x from 0.02 to 0.5
    depth, _ = cast(sim, near=0.05)
    np.testing.assert_allclose(depth, 0.5, rtol=1e-12)
    depth, ids = cast(sim, near=0.05, far=0.5)
    np.testing.assert_array_equal(depth, 0.0)
    np.testing.assert_array_equal(ids, -1)


def test_the_table_follows_the_bodies(sim):
    """Hidden, moved, turned and removed bodies are drawn as the Sim holds them."""
    (box,) = sim.obstacles.add_static_boxes((0.5, 0.5, 0.5), (0.5, 0.5, 0.5, 1.0), [(3.0, 0.0, 0.0)])
    middle = SIZE // 2
    assert cast(sim)[0][middle, middle] == pytest.approx(2.5)
    sim.obstacles.set_visible(box, False, (0.5, 0.5, 0.5, 1.0))
    assert cast(sim)[0][middle, middle] == 0.0
    sim.obstacles.set_visible(box, True, (0.5, 0.5, 0.5, 1.0))
    sim.obstacles.move_static(box, (4.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    assert cast(sim)[0][middle, middle] == pytest.approx(3.5)
    # turned 45 degrees about z: the middle ray meets the vertical edge, half a diagonal nearer than the centre
    sim.obstacles.move_static(box, (4.0, 0.0, 0.0), (0.0, 0.0, math.sin(math.pi / 8), math.cos(math.pi / 8)))
    assert cast(sim)[0][middle, middle] == pytest.approx(4.0 - math.sqrt(0.5), abs=1e-12)
    sim.obstacles.remove_body(box)
    assert not cast(sim)[0].any()


def test_a_movable_body_is_drawn_where_the_physics_put_it(sim):
    body = sim.obstacles.add_movable_box((0.5, 0.5, 0.5), (0.5, 0.5, 0.5, 1.0))
    sim.obstacles.move_static(body, (3.0, 0.0, 2.0), (0.0, 0.0, 0.0, 1.0))
    sim.obstacles.set_mass(body, 1.0, (0.1, 0.1, 0.1))
    sim.step(30)  # falling: drawn where body_poses last read it
    (position,), _ = sim.obstacles.body_poses([body])
    assert position[2] < 2.0
    depth, ids = cast(sim, eye=(0.0, 0.0, position[2]))
    assert depth[SIZE // 2, SIZE // 2] == pytest.approx(2.5, abs=1e-9)
    assert ids[SIZE // 2, SIZE // 2] == body


def depth_buffer_step(z: np.ndarray, near: float, far: float) -> np.ndarray:
    """Metres one float32 step of a depth buffer near 1 spans at depth z: the buffer holds
    (1/near - 1/z) / (1/near - 1/far), so dz = z^2 (1/near - 1/far) 2^-24."""
    return z**2 * (1 / near - 1 / far) * 2.0**-24


def test_agrees_with_tiny_renderer_on_generated_scenes():
    """ClutterFly-v1 scenes from the drone's camera along random flights, cast through TinyRenderer's sample points
    (its principal point is half a pixel off): on the faces of boxes, away from every edge (the 3x3 block around a
    pixel shows one body in both images), the depths agree within 4 steps of TinyRenderer's float32 depth buffer
    (a step is 0.12 mm at 10 m). Cylinders are left to the closed forms above: TinyRenderer draws them as polygon
    prisms."""
    worst, compared = 0.0, 0
    for seed in range(2):
        env = gym.make("ClutterFly-v1", sensors=("camera",), camera_size=(64, 48), camera_renderer="tiny")
        env.reset(seed=seed)
        env.action_space.seed(seed)
        u = env.unwrapped
        sim, camera = u.sim, u.sensors[0]
        c, i = camera.config, camera.intrinsics
        bodies, kinds = sim.primitives.arrays()[:2]
        boxes = bodies[kinds == BOX]
        for _ in range(8):
            *_, terminated, truncated, _ = env.step(0.3 * env.action_space.sample())
            state = u.robot.state()
            row = state.link(c.link)
            eye, rotation = state.links.position[row], state.links.rotation[row]
            _, buffer, tiny_ids = sim.rendering.camera_image(c.width, c.height, _view_matrix(eye, rotation),
                                                             camera.projection, True, behind=state.body)
            tiny = c.far * c.near / (c.far - (c.far - c.near) * buffer)
            axes = np.array([rotation[:, 0], -rotation[:, 1], -rotation[:, 2]])
            rays, ids = sim.rendering.ray_cast_image(c.width, c.height, eye, axes, (i.fx, i.fy, i.cx, i.cy), c.near,
                                                     c.far)
            same = (ndimage.minimum_filter(ids, 3) == ids) & (ndimage.maximum_filter(ids, 3) == ids)
            same &= (ndimage.minimum_filter(tiny_ids, 3) == ids) & (ndimage.maximum_filter(tiny_ids, 3) == ids)
            faces = same & np.isin(ids, boxes)
            error = np.abs(rays[faces] - tiny[faces]) / depth_buffer_step(tiny[faces], c.near, c.far)
            worst, compared = max(worst, float(error.max(initial=0.0))), compared + int(faces.sum())
            if terminated or truncated:
                break
        env.close()
    assert compared > 5000
    assert worst < 4.0


def test_env_boundary():
    env = gym.make("ClutterFly-v1", sensors=("camera",), camera_modes=("depth", "segmentation"))
    env.reset(seed=0)
    u = env.unwrapped
    assert u.sensors[0].config.renderer == "rays" and not u.sim.visuals
    obs, *_ = env.step(np.zeros(4, dtype=np.float32))
    assert obs["camera_depth"].dtype == np.float32 and (obs["camera_depth"] > 0).mean() > 0.9
    classes = set(np.unique(obs["camera_segmentation"]).tolist())
    assert classes <= {1, 2, 4} and 2 in classes  # ground, obstacle, goal; never nothing inside the walls
    env.close()
    rgbd = gym.make("ClutterFly-v1", sensors=("camera",), camera_modes=("rgb", "depth"))
    assert rgbd.unwrapped.sensors[0].config.renderer == "tiny"  # the default renderer draws what is asked for
    rgbd.close()
    with pytest.raises(ValueError, match=r"camera_renderer='rays' draws only .*rgb"):
        gym.make("ClutterFly-v1", sensors=("camera",), camera_modes=("rgb", "depth"), camera_renderer="rays")
