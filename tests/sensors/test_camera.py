"""The camera against analytic answers: depth of a wall and of the floor, where an edge falls, segmentation."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import empty_scene
from scipy.ndimage import binary_erosion

from clutter_gym.sensors import SEGMENTATION_CLASSES

CAMERA_HEIGHT = 0.15  # axle 0.05 m above the floor + camera joint 0.10 m (diffbot.urdf)
LENS_X = 0.165  # camera joint x in base_link
GROUND, OBSTACLE, NOTHING = (SEGMENTATION_CLASSES.index(c) for c in ("ground", "obstacle", "nothing"))


def look(make_env, obstacles=(), size=(84, 64), **kwargs):
    env = make_env(sensors=("camera",), camera_modes=("rgb", "depth", "segmentation"), camera_size=size, **kwargs)
    obs, _ = env.reset(options={"scene": empty_scene(obstacles=obstacles)})
    return env.unwrapped.sensors[0].intrinsics, obs


def test_a_wall_square_to_the_axis_has_one_depth(make_env):
    _, obs = look(make_env)
    wall = obs["camera_segmentation"] == OBSTACLE
    assert wall.sum() > 500
    # the arena wall's inner face is at x = 3 m; depth is measured along the optical axis, not along the ray
    np.testing.assert_allclose(obs["camera_depth"][wall], 3.0 - LENS_X, atol=2e-3)


def test_floor_depth_per_row_matches_the_pinhole_model(make_env):
    k, obs = look(make_env)
    rows = np.arange(k.height)
    floor_rows = [v for v in rows if (obs["camera_segmentation"][v] == GROUND).all()]
    assert len(floor_rows) > 20
    for v in floor_rows:
        expected = CAMERA_HEIGHT * k.fy / (v - k.cy)  # a ray through row v meets the floor at this depth
        np.testing.assert_allclose(obs["camera_depth"][v], expected, rtol=1e-3)


@pytest.mark.parametrize("edge_y", [-0.3, -0.17, -0.05])
def test_a_box_edge_falls_on_the_predicted_column(make_env, edge_y):
    """A wide box whose right edge is at y = edge_y (the camera looks along +x; +y is the image's left)."""
    box = {"shape": "box", "position": [1.5, edge_y + 1.0], "size": [0.3, 2.0, 0.5]}
    k, obs = look(make_env, [box])
    row = obs["camera_depth"][int(k.cy) + 2]
    on_box = np.abs(row - (1.35 - LENS_X)) < 0.01
    first_off = int(np.argmin(on_box))
    assert on_box[:first_off].all() and not on_box[first_off:].any()
    u_edge = k.cx - k.fx * edge_y / (1.35 - LENS_X)  # column of the edge, pixel-index coordinates
    assert first_off - 1 < u_edge <= first_off


def test_segmentation_and_colour_see_the_scene(make_env):
    k, obs = look(make_env, size=(84, 84))
    seg = obs["camera_segmentation"]
    assert (seg[0] == NOTHING).all()  # above the 0.5 m walls: nothing
    assert (seg[-1] == GROUND).all()
    assert obs["camera_rgb"].dtype == np.uint8 and obs["camera_rgb"].shape == (84, 84, 3)
    # the floor and the wall differ in colour
    floor_colour = obs["camera_rgb"][seg == GROUND].mean(axis=0)
    wall_colour = obs["camera_rgb"][seg == OBSTACLE].mean(axis=0)
    assert np.abs(floor_colour - wall_colour).max() > 20
    assert (obs["camera_depth"][seg == NOTHING] == 0).all()  # no return reads 0


def test_depth_noise_on_a_wall_matches_the_harsh_profile(make_env):
    """Harsh depth on the arena wall (z = 2.835 m), away from its borders so that lateral jitter and edge holes
    do not reach: sigma(z) = 0.010 z^2 = 80 mm with a 23 mm quantisation step, holes at hole_prob = 0.15."""
    _, clean = look(make_env, size=(320, 240))
    _, noisy = look(make_env, size=(320, 240), noise="harsh")
    wall = clean["camera_segmentation"] == OBSTACLE
    interior = binary_erosion(wall, iterations=3)
    assert interior.sum() > 6000
    depth = noisy["camera_depth"][interior]
    holes = depth == 0
    n = interior.sum()
    assert abs(holes.mean() - 0.15) < 5 * np.sqrt(0.15 * 0.85 / n)
    z = 3.0 - LENS_X
    error = depth[~holes] - z
    step = 0.00285 * z**2
    expected = np.hypot(0.010 * z**2, step / np.sqrt(12))  # Gaussian axial noise, then rounding to the step
    # the sample std of ~6,000 pixels has a relative standard error of 0.9%; 5% is over five of them
    assert abs(error.std() / expected - 1.0) < 0.05
    # one per-episode bias, within +-(0.011 + 0.001 z); the mean of ~6,000 pixels is good to 1 mm
    assert abs(error.mean()) < 0.011 + 0.001 * z + 5 * expected / np.sqrt(error.size)


def test_the_render_leaves_every_colour_as_it_was(make_env):
    """The robot is hidden during its own camera's frame (TinyRenderer pays for geometry behind the eye) and
    parked obstacles are invisible; after a frame the robot's colours are back, and active obstacles are shown."""
    import pybullet as pb

    env = make_env(sensors=("camera",), render_mode="rgb_array")
    env.reset(seed=0)
    u = env.unwrapped
    cid = u.sim.client_id
    before = [d[7] for d in pb.getVisualShapeData(u.robot.body, physicsClientId=cid)]
    for _ in range(3):
        env.step(np.zeros(2, dtype=np.float32))
    assert [d[7] for d in pb.getVisualShapeData(u.robot.body, physicsClientId=cid)] == before
    for _ in range(5):
        env.reset()
    pool = u.arena._pool
    alpha = {b: pb.getVisualShapeData(b, physicsClientId=cid)[0][7][3] for b in pool._parked}
    assert alpha and all(a == 0.0 for a in alpha.values())
    assert all(pb.getVisualShapeData(b, physicsClientId=cid)[0][7][3] == 1.0 for b in pool.placed.values())
