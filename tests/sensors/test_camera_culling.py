"""View culling: hiding the static bodies no pixel of the camera can show (Sim.culler.outside_view) leaves RGB, depth
and segmentation exactly as they were, and every body gets its colour back after the frame."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pybullet as pb
import pytest
from helpers import empty_scene

from clutter_gym.sensors.camera import Camera, CameraConfig, _view_matrix
from clutter_gym.sim import Sim
from clutter_gym.util.view_culling import CULL_MARGIN

MODES = ("rgb", "depth", "segmentation")
LENS_X = 0.165  # camera joint x in base_link (diffbot.urdf); the lens is 0.15 m above the floor


def frames_agree(env) -> tuple[np.ndarray, list[int]]:
    """Render the camera's frame with and without culling, assert they are identical and that no body with a pixel
    in view was culled; returns (body id per pixel, bodies culled)."""
    u = env.unwrapped
    sim, camera = u.sim, u.sensors[0]
    c = camera.config
    state = u.robot.state()
    view = _view_matrix(*sim.link_frame(state.body, state.link_index[c.link]))
    args = (c.width, c.height, view, camera.projection, True)
    plain = sim.rendering.camera_image(*args, behind=state.body, cull=False)
    culled = sim.rendering.camera_image(*args, behind=state.body, cull=True)
    for name, a, b in zip(("rgb", "depth buffer", "segmentation"), plain, culled):
        np.testing.assert_array_equal(a, b, err_msg=f"{name} differs")
    culled_ids = sim.culler.outside_view(view, camera.projection, c.width, c.height)
    assert not np.isin(plain[2], culled_ids).any(), "a body in view was culled"
    return plain[2], culled_ids


@pytest.mark.parametrize(("size", "far"), [((84, 84), 10.0), ((64, 48), 2.5)])
def test_culling_leaves_generated_scenes_identical(make_env, size, far):
    """Three generated layouts in turn (the pool moves, parks and reuses bodies), each seen from poses across the
    arena in every direction."""
    env = make_env(sensors=("camera",), camera_modes=MODES, camera_size=size, camera_far=far)
    culled_total = 0
    for seed in range(3):
        env.reset(seed=seed)
        for (x, y), yaw in itertools.product(((0.0, 0.0), (-2.2, 1.9), (2.3, -2.4)), np.linspace(-3, 3, 7)):
            env.unwrapped.robot.reset_pose(x, y, yaw)
            culled_total += len(frames_agree(env)[1])
    assert culled_total > 3 * 21 * 2


def sweep(env, body: int, poses, axis: int) -> tuple[int, int]:
    """Frames along ``poses`` (robot x, y, yaw); returns (fewest image columns (axis 0) or rows (axis 1) ``body``
    showed in when in view, frames that culled it)."""
    fewest, culled = 10**9, 0
    for pose in poses:
        env.unwrapped.robot.reset_pose(*pose)
        segmentation, culled_ids = frames_agree(env)
        lines = int((segmentation == body).any(axis=axis).sum())
        fewest = min(fewest, lines or fewest)
        culled += body in culled_ids
    return fewest, culled


def body_at(sim, x: float, y: float) -> int:
    """The body whose origin is above (x, y)."""
    for body in sim.body_ids():
        position = pb.getBasePositionAndOrientation(body, physicsClientId=sim.client_id)[0]
        if abs(position[0] - x) + abs(position[1] - y) < 1e-6:
            return body
    raise LookupError((x, y))


def test_bodies_crossing_the_edges_of_the_image(make_env):
    """A cylinder crossing the left edge and a box the right edge (the robot turns in 0.25 degree steps, a third of
    a pixel), and a box above the floor crossing the top edge (the robot moves away in 1 cm steps): the frames
    stay identical, each body shows in a single column or row at the edge, and is culled just past it."""
    cylinder = {"shape": "cylinder", "radius": 0.3, "height": 0.5, "position": [1.5, 1.0]}
    box = {"shape": "box", "size": [0.4, 0.4, 0.5], "position": [1.2, -1.0], "yaw": 0.4}
    high = {"shape": "box", "size": [0.3, 0.3, 0.2], "position": [-2.0, 0.0], "z": 1.0}
    mirrored = [{**o, "position": [o["position"][0], -o["position"][1]]} for o in (cylinder, box, high)]
    env = make_env(sensors=("camera",), camera_modes=MODES)
    for obstacles in (mirrored, [cylinder, box, high]):  # the second reset moves the same bodies
        env.reset(options={"scene": empty_scene(start=(-0.3, 0.0, 0.0), obstacles=obstacles)})
    sim = env.unwrapped.sim
    half_fov = env.unwrapped.sensors[0].config.vertical_fov / 2  # a square image: the horizontal one too
    for (x, y), side in (((1.5, 1.0), 1), ((1.2, -1.0), -1)):
        bearing = math.atan2(y, x - (-0.3 + LENS_X))
        yaws = bearing - side * (half_fov + np.radians(np.arange(-16.0, 16.0, 0.25)))
        fewest, culled = sweep(env, body_at(sim, x, y), [(-0.3, 0.0, yaw) for yaw in yaws], axis=0)
        assert fewest == 1 and culled > 0
    # the high box's bottom face (z = 1 m) enters the top row (1 - 0.15) / tan(29 deg) = 1.53 m from the camera
    poses = [(-2.0 + d + LENS_X, 0.0, math.pi) for d in np.arange(1.0, 1.7, 0.01)]
    fewest, culled = sweep(env, body_at(sim, -2.0, 0.0), poses, axis=1)
    assert fewest == 1 and culled > 0


@pytest.mark.parametrize(("size", "far"), [((84, 84), 10.0), ((64, 48), 3.0)])
def test_no_pixel_ray_meets_a_culled_body(size, far):
    """Boxes placed just inside and just outside the edges of the image of a camera in random poses: the ray of
    every pixel (where TinyRenderer samples it, see CameraConfig.intrinsics), between the near and far planes,
    misses the sphere through the corners of every box that outside_view names, and many named ones come within
    a few pixels of being seen."""
    config = CameraConfig(width=size[0], height=size[1], far=far)
    camera, k = Camera(config), config.intrinsics
    rng = np.random.default_rng(0)
    half_extents = rng.uniform(0.02, 0.3, (200, 3))
    radii = np.linalg.norm(half_extents, axis=1)
    columns, rows = np.meshgrid(np.arange(k.width), np.arange(k.height))
    rays = np.column_stack([np.ones(columns.size), -(columns.ravel() - k.cx) / k.fx, -(rows.ravel() - k.cy) / k.fy])
    edges = rays[(columns.ravel() % (k.width - 1) == 0) | (rows.ravel() % (k.height - 1) == 0)]
    sim = Sim()
    try:
        bodies = [body for he in half_extents
                  for body in sim.obstacles.add_static_boxes(he, (0.5, 0.5, 0.5, 1.0), [(0, 0, 0)])]
        near_edge = 0
        for _ in range(6):
            rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            rotation *= np.sign(np.linalg.det(rotation))  # columns: ahead, left, up
            eye = rng.uniform(-1, 1, 3)
            # camera frame: a point on the ray of an edge pixel, moved out of the image by its radius and -1 to 3 pixels
            ray = edges[rng.integers(len(edges), size=len(bodies))]
            outward = np.where(np.abs(ray[:, 1:]) * [k.fx, k.fy] >= np.array([k.cx, k.cy]) - 1, np.sign(ray[:, 1:]), 0)
            depth = rng.uniform(0.1, far, len(bodies))
            offset = radii + CULL_MARGIN + depth / k.fx * rng.uniform(-1, 3, len(bodies))
            centres = np.column_stack([depth, ray[:, 1:] * depth[:, None] + offset[:, None] * outward])
            for body, centre in zip(bodies, centres):
                sim.obstacles.move_static(body, eye + rotation @ centre, (0.0, 0.0, 0.0, 1.0))
            for body in sim.culler.outside_view(_view_matrix(eye, rotation), camera.projection, k.width, k.height):
                i = bodies.index(body)
                along = np.clip(rays @ centres[i] / (rays * rays).sum(axis=1), config.near, far)
                miss = np.linalg.norm(rays * along[:, None] - centres[i], axis=1).min() - radii[i]
                assert miss > 0, f"a pixel ray meets culled body {body}"
                near_edge += miss < CULL_MARGIN + 3 * depth[i] / k.fx  # within 3 pixels of the margin
        assert near_edge > 40
    finally:
        sim.close()


def colours(sim) -> dict[tuple[int, int], tuple]:
    """(body, link) -> rgba of every visual shape in the world."""
    return {(d[0], d[1]): d[7] for b in sim.body_ids() for d in pb.getVisualShapeData(b, physicsClientId=sim.client_id)}


def test_culled_bodies_get_their_colours_back(make_env):
    """Two envs run the same resets (so the pool parks and reuses bodies) and actions, one culling and one not:
    after every step each visual shape, the robot's and the parked bodies' included, has the same colour in both."""
    culling, plain = (make_env(sensors=("camera",), camera_modes=MODES) for _ in range(2))
    plain.unwrapped.sim.culler.outside_view = lambda *args: []
    rng = np.random.default_rng(0)
    for seed in range(4):
        for env in (culling, plain):
            env.reset(seed=seed)
        assert colours(culling.unwrapped.sim) == colours(plain.unwrapped.sim)
        for action in rng.uniform(-1, 1, (5, 2)).astype(np.float32):
            for env in (culling, plain):
                env.step(action)
            assert colours(culling.unwrapped.sim) == colours(plain.unwrapped.sim)
    assert any(rgba[3] == 0.0 for rgba in colours(culling.unwrapped.sim).values())  # parked bodies exist
    assert frames_agree(culling)[1]  # and frames cull
    assert colours(culling.unwrapped.sim) == colours(plain.unwrapped.sim)
