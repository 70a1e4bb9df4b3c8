"""ViewCuller against the analytic frustum of a pinhole camera: spheres just inside and just outside each kind of
plane (a side of the image widened by a pixel, the plane of the eye, the far plane), and its cache of the shown
bodies after moves, colour changes and removals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.util.view_culling import CULL_MARGIN, ViewCuller

WIDTH, HEIGHT = 64, 48
FOVY = math.radians(58.0)
NEAR, FAR = 0.05, 5.0
EPS = 1e-6  # metres either side of the boundary
SHOWN = (0.5, 0.5, 0.5, 1.0)


def projection(width: int = WIDTH, height: int = HEIGHT) -> list[float]:
    """OpenGL perspective projection, column-major."""
    f, aspect = 1.0 / math.tan(FOVY / 2), width / height
    m = np.array([
        [f / aspect, 0, 0, 0],
        [0, f, 0, 0],
        [0, 0, (FAR + NEAR) / (NEAR - FAR), 2 * FAR * NEAR / (NEAR - FAR)],
        [0, 0, -1, 0],
    ])
    return m.T.ravel().tolist()


def view(eye, rotation) -> list[float]:
    """OpenGL view matrix, column-major, of a camera at ``eye`` whose eye axes (right, up, backwards) are the
    columns of ``rotation``: a world point p has eye coordinates rotation.T @ (p - eye)."""
    m = np.eye(4)
    m[:3, :3] = rotation.T
    m[:3, 3] = -rotation.T @ eye
    return m.T.ravel().tolist()


EYE = np.array([0.4, -1.2, 0.7])
ROTATION = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
ROTATION *= np.sign(np.linalg.det(ROTATION))


def named(centre_eye, radius: float) -> bool:
    """Whether a culler holding one body at ``centre_eye`` (eye coordinates, metres) names it for the camera."""
    culler = ViewCuller()
    culler.add(7, radius, SHOWN)
    culler.move(7, EYE + ROTATION @ np.asarray(centre_eye, dtype=float))
    return culler.outside_view(view(EYE, ROTATION), projection(), WIDTH, HEIGHT) == [7]


def side_tangent(axis: int) -> float:
    """tan of the half angle, widened by a pixel, of the image along x (axis 0) or y (axis 1)."""
    half = math.tan(FOVY / 2) * (WIDTH / HEIGHT if axis == 0 else 1.0)
    return half * (1.0 + 2.0 / (WIDTH if axis == 0 else HEIGHT))


@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("depth", [0.3, 2.0, 4.5])
def test_a_sphere_just_past_a_side_is_named_and_just_inside_is_not(axis, sign, depth):
    """The side plane through the eye at half angle theta: a centre at depth d and lateral offset x lies
    (d sin theta - x cos theta) inside it, so the sphere leaves the view at x = (d sin theta + R) / cos theta."""
    radius = 0.2
    theta = math.atan(side_tangent(axis))
    boundary = (depth * math.sin(theta) + radius + CULL_MARGIN) / math.cos(theta)
    for offset, expected in ((boundary + EPS, True), (boundary - EPS, False)):
        centre = [0.0, 0.0, -depth]
        centre[axis] = sign * offset
        assert named(centre, radius) is expected, (offset, boundary)


def test_a_sphere_behind_the_eye_is_named_once_wholly_behind():
    radius = 0.3
    r = radius + CULL_MARGIN
    assert named([0.0, 0.0, r + EPS], radius)
    assert not named([0.0, 0.0, r - EPS], radius)  # it reaches in front of the eye
    assert named([0.5, -2.0, 1.5], radius)  # behind and off to the side


def test_a_sphere_beyond_the_far_plane_is_named_once_wholly_beyond():
    radius = 0.1
    r = radius + CULL_MARGIN
    assert named([0.0, 0.0, -(FAR + r) - EPS], radius)
    assert not named([0.0, 0.0, -(FAR + r) + EPS], radius)


def test_a_sphere_straddling_the_eye_or_in_view_is_never_named():
    assert not named([0.0, 0.0, 0.0], 0.01)  # around the eye
    assert not named([0.0, 0.0, -1.0], 0.01)  # on the optical axis
    assert not named([0.0, 0.0, -1.0], 50.0)  # holds the whole frustum


def test_the_image_size_widens_the_sides_by_a_pixel():
    """A sphere just past the right side of a 1024-pixel-wide image, widened by its pixel, is still inside the side
    of a 64-pixel-wide image with the same field of view, widened by its larger pixel."""
    culler = ViewCuller()
    culler.add(1, 0.0, SHOWN)
    narrow, wide = (math.atan(math.tan(FOVY / 2) * WIDTH / HEIGHT * (1 + 2 / w)) for w in (1024, WIDTH))
    x = (math.sin(narrow) + CULL_MARGIN + 0.005) / math.cos(narrow)  # at depth 1 m, 5 mm past the 1024 side
    assert math.sin(wide) - x * math.cos(wide) > -CULL_MARGIN  # inside the 64 side
    culler.move(1, EYE + ROTATION @ np.array([x, 0.0, -1.0]))
    camera = view(EYE, ROTATION)
    assert culler.outside_view(camera, projection(1024, 768), 1024, 768) == [1]
    assert culler.outside_view(camera, projection(WIDTH, HEIGHT), WIDTH, HEIGHT) == []


def test_moves_colour_changes_and_removals_reach_the_next_answer():
    culler = ViewCuller()
    camera = (view(EYE, ROTATION), projection(), WIDTH, HEIGHT)
    inside, behind = EYE + ROTATION @ np.array([0.0, 0.0, -1.0]), EYE + ROTATION @ np.array([0.0, 0.0, 2.0])
    for body in (3, 4):
        culler.add(body, 0.1, SHOWN)
        culler.move(body, behind)
    assert culler.outside_view(*camera) == [3, 4]
    culler.move(3, inside)
    assert culler.outside_view(*camera) == [4]
    culler.move(3, behind)
    assert culler.outside_view(*camera) == [3, 4]
    culler.set_colour(4, (0.5, 0.5, 0.5, 0.0))  # hidden: never named, no colour to restore
    assert culler.outside_view(*camera) == [3]
    with pytest.raises(KeyError):
        culler.colour(4)
    culler.move(4, inside)  # moved while hidden: shown again where it now is
    culler.set_colour(4, (0.1, 0.2, 0.3, 1.0))
    assert culler.outside_view(*camera) == [3]
    assert culler.colour(4) == (0.1, 0.2, 0.3, 1.0)
    culler.set_colour(3, None)
    assert culler.outside_view(*camera) == []
    culler.set_colour(3, SHOWN)
    culler.remove(3)
    culler.set_colour(3, SHOWN)  # removed: no longer tracked
    culler.move(4, behind)
    assert culler.outside_view(*camera) == [4]


def test_untracked_bodies_are_ignored():
    culler = ViewCuller()
    culler.move(9, (1.0, 2.0, 3.0))
    culler.set_colour(9, SHOWN)
    culler.remove(9)
    assert culler.outside_view(view(EYE, ROTATION), projection(), WIDTH, HEIGHT) == []


def test_a_body_added_hidden_is_never_named():
    culler = ViewCuller()
    culler.add(2, 0.1, (1.0, 0.0, 0.0, 0.0))
    culler.move(2, EYE + ROTATION @ np.array([0.0, 0.0, 2.0]))
    assert culler.outside_view(view(EYE, ROTATION), projection(), WIDTH, HEIGHT) == []
