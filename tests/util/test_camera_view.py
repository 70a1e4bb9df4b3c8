"""The look-at camera helpers: pybullet's matrices rebuilt, where points land, and where cameras are put."""

from __future__ import annotations

import numpy as np
import pytest

from clutter_gym.sim import Sim, pb
from clutter_gym.util.camera_view import (
    CameraView,
    between,
    chase_eye,
    fitting_distance,
    look_at,
    orbit_angles,
    perspective,
    pull_in,
)

CAMERAS = [((1.0, 2.0, 3.0), (0.0, 0.0, 0.0)), ((-3.0, 0.5, 3.2), (0.3, -0.2, 0.4)),
           ((0.2, -3.0, 2.5), (0.0, 0.0, 0.0))]


def _pybullet_matrix(values) -> np.ndarray:
    return np.array(values, dtype=float).reshape(4, 4).T  # pybullet's lists are column-major


@pytest.mark.parametrize(("eye", "target"), CAMERAS)
def test_look_at_is_pybullets_view_matrix(eye, target):
    expected = _pybullet_matrix(pb.computeViewMatrix(eye, target, (0.0, 0.0, 1.0)))
    np.testing.assert_allclose(look_at(eye, target), expected, atol=1e-6)


@pytest.mark.parametrize(("fov", "aspect"), [(60.0, 4 / 3), (45.0, 1.0), (90.0, 16 / 9)])
def test_perspective_is_pybullets_projection_matrix(fov, aspect):
    expected = _pybullet_matrix(pb.computeProjectionMatrixFOV(fov, aspect, 0.05, 50.0))
    np.testing.assert_allclose(perspective(fov, aspect), expected, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize(("eye", "target"), CAMERAS)
def test_orbit_angles_put_pybullets_gui_camera_at_the_eye(eye, target):
    distance, yaw, pitch = orbit_angles(eye, target)
    view = _pybullet_matrix(pb.computeViewMatrixFromYawPitchRoll(target, distance, yaw, pitch, 0.0, 2))
    np.testing.assert_allclose(view, look_at(eye, target), atol=1e-5)


def test_projected_points_land_on_the_pixels_pybullet_draws_them_on():
    """A small marker disc moved to each point shows up, in pybullet's segmentation, centred where the helper
    projects the point (the disc is 1 cm thick, well under a pixel's width at these distances)."""
    sim = Sim(visuals=True)
    try:
        marker = sim.add_marker("probe", 0.03, (1.0, 0.0, 0.0, 1.0))
        points = [(0.0, 0.0, 0.0), (0.6, -0.4, 0.3), (-0.9, 0.5, -0.2), (1.1, 0.9, 0.6), (-0.7, -0.8, 0.9)]
        for eye, target in CAMERAS:
            view = CameraView(eye, target, 320, 240)
            for point in points:
                sim.obstacles.move_static(marker, point, (0.0, 0.0, 0.0, 1.0))
                seg = sim.rendering.render_segmentation(320, 240, eye, target)
                rows, cols = np.nonzero(seg == marker)
                (pixel,), (in_front,) = view.project([point])
                assert in_front
                if not (3 <= pixel[0] <= 316 and 3 <= pixel[1] <= 236):
                    assert len(rows) < 30  # out of frame, or cut by its edge
                    continue
                assert len(rows) >= 4, (eye, point)
                np.testing.assert_allclose([cols.mean(), rows.mean()], pixel, atol=0.4)
    finally:
        sim.close()


def test_points_behind_the_camera_are_flagged_and_depth_and_scale_follow_distance():
    view = CameraView((0.0, -2.0, 0.0), (0.0, 0.0, 0.0), 320, 240)
    _, in_front = view.project([(0.0, 0.0, 0.0), (0.0, -3.0, 0.0)])
    assert in_front.tolist() == [True, False]
    np.testing.assert_allclose(view.depth([(0.0, 0.0, 0.0), (5.0, 2.0, 1.0)]), [2.0, 4.0])
    near, far = view.pixels_per_metre([(0.0, -1.0, 0.0), (0.0, 1.0, 0.0)])
    assert near == pytest.approx(3.0 * far)


def test_chase_eye_sits_behind_and_above_the_robot_away_from_the_goal():
    eye = chase_eye((1.0, 1.0, 1.0), (4.0, 5.0, 1.0), back=0.5, up=0.3)
    np.testing.assert_allclose(eye, (1.0 - 0.3, 1.0 - 0.4, 1.3))
    np.testing.assert_allclose(chase_eye((0.0, 0.0, 1.0), (0.0, 0.0, 3.0), 0.5, 0.3), (-0.5, 0.0, 1.3))


def test_between_keeps_the_robot_and_the_goal_in_frame():
    robot, goal = (0.0, 0.0, 1.0), (3.0, 0.0, 1.0)
    eye = chase_eye(robot, goal, 0.6, 0.4)
    target = between(robot, goal, eye, 0.35)
    pixels, in_front = CameraView(tuple(eye), tuple(target), 320, 240).project([robot, goal])
    assert in_front.all() and np.all((pixels >= 0) & (pixels <= [319, 239]))
    np.testing.assert_allclose(between(robot, goal, eye, 0.0), robot)


def test_pull_in_stops_the_arm_short_of_the_hit():
    anchor, eye = np.zeros(3), np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(pull_in(anchor, eye, 1.0, 0.1, 0.2), eye)
    np.testing.assert_allclose(pull_in(anchor, eye, 0.6, 0.1, 0.2), (0.5, 0.0, 0.0))
    np.testing.assert_allclose(pull_in(anchor, eye, 0.05, 0.1, 0.2), (0.2, 0.0, 0.0))


def test_fitting_distance_is_the_nearest_that_keeps_the_points_inside():
    target, direction = np.zeros(3), np.array([0.0, -0.5, np.sqrt(0.75)])
    points = np.array([(-2.0, 1.0, 0.0), (2.0, -1.0, 0.0)])
    distance = fitting_distance(points, target, direction, 1.0, 30.0, 320, 240, inset=0.2)
    for d, inside in ((distance, True), (distance * 0.97, False)):
        view = CameraView(tuple(target + d * direction), tuple(target), 320, 240)
        ndc, _ = view.normalised(points)
        assert bool(np.abs(ndc).max() <= 0.8 + 1e-3) is inside
    assert fitting_distance(points[:1] * 0, target, direction, 1.0, 30.0, 320, 240, 0.2) == 1.0
    assert fitting_distance(points * 100, target, direction, 1.0, 30.0, 320, 240, 0.2) == 30.0
