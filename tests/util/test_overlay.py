"""The marks drawn over rgb_array frames, on plain images: rings where the points project, arrows towards points
out of view, a trail that leaves out what is behind the camera."""

from __future__ import annotations

import numpy as np
from helpers import ring_pixels

from clutter_gym.util.camera_view import CameraView
from clutter_gym.util.overlay import GOAL_COLOUR, LEAST_RING_PX, ROBOT_COLOUR, draw_marks

VIEW = CameraView((0.0, -3.0, 3.0), (0.0, 0.0, 0.0), 320, 240)
GREY = np.full((240, 320, 3), 128, dtype=np.uint8)


def _centre(mask: np.ndarray) -> np.ndarray:
    rows, cols = np.nonzero(mask)
    return np.array([cols.mean(), rows.mean()])


def test_rings_surround_the_projected_points_and_the_frame_is_not_changed_in_place():
    frame = GREY.copy()
    robot, goal = (0.8, -0.5, 0.1), (-1.0, 1.0, 0.0)
    out = draw_marks(frame, VIEW, (robot, 0.17), (goal, 0.3), np.zeros((0, 3)))
    assert np.array_equal(frame, GREY) and out.shape == frame.shape and out.dtype == np.uint8
    pixels, _ = VIEW.project([robot, goal])
    for colour, pixel in ((ROBOT_COLOUR, pixels[0]), (GOAL_COLOUR, pixels[1])):
        mask = ring_pixels(out, colour)
        np.testing.assert_allclose(_centre(mask), pixel, atol=1.0)
        rows, cols = np.nonzero(mask)
        assert np.hypot(cols - pixel[0], rows - pixel[1]).min() >= LEAST_RING_PX - 1  # a ring, not a dot


def test_a_far_goal_still_gets_a_ring_of_readable_size():
    far = CameraView((0.0, -40.0, 30.0), (0.0, 0.0, 0.0), 320, 240)
    out = draw_marks(GREY, far, ((0.0, 0.0, 0.0), 0.05), ((1.0, 0.0, 0.0), 0.05), np.zeros((0, 3)))
    assert ring_pixels(out, GOAL_COLOUR).sum() >= 2 * np.pi * LEAST_RING_PX


def test_a_goal_out_of_view_gets_an_arrow_on_the_edge_it_lies_beyond():
    beyond_right = (40.0, 0.0, 0.0)
    out = draw_marks(GREY, VIEW, ((0.0, 0.0, 0.0), 0.1), (beyond_right, 0.3), np.zeros((0, 3)))
    cols = np.nonzero(ring_pixels(out, GOAL_COLOUR))[1]
    assert len(cols) > 20 and cols.min() > 280
    behind = (0.0, -10.0, 3.0)  # behind the camera, which looks along +y: the arrow points down, towards it
    out = draw_marks(GREY, VIEW, ((0.0, 0.0, 0.0), 0.1), (behind, 0.3), np.zeros((0, 3)))
    rows = np.nonzero(ring_pixels(out, GOAL_COLOUR))[0]
    assert len(rows) > 20 and rows.min() > 200


def test_the_trail_is_drawn_between_its_points_and_not_behind_the_camera():
    trail = np.array([(x, 0.0, 0.0) for x in np.linspace(-1.5, 0.0, 30)])
    out = draw_marks(GREY, VIEW, (trail[-1], 0.1), ((0.0, 2.0, 0.0), 0.3), trail)
    changed = np.any(out != GREY, axis=2)
    start, _ = VIEW.project(trail[:1])
    row, col = int(round(start[0, 1])), int(round(start[0, 0]))
    assert changed[row - 2:row + 3, col - 2:col + 3].any()  # its oldest point is drawn, faintly
    behind = np.array([(0.0, -5.0, 3.0), (0.2, -5.0, 3.0)])
    alone = draw_marks(GREY, VIEW, ((0.0, 0.0, 0.0), 0.1), ((0.0, 2.0, 0.0), 0.3), np.zeros((0, 3)))
    assert np.array_equal(draw_marks(GREY, VIEW, ((0.0, 0.0, 0.0), 0.1), ((0.0, 2.0, 0.0), 0.3), behind), alone)
