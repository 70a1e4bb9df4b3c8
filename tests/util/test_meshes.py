"""The cylinder-standing-in prism: area-preserving, correctly wound, open at the bottom."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.util.meshes import prism_mesh


@pytest.mark.parametrize("sides", [16, 64])
def test_prism_has_the_circle_area_and_height(sides):
    vertices, indices = prism_mesh(0.3, 0.5, sides)
    v = np.array(vertices)
    ring = v[:sides, :2]
    x, y = ring[:, 0], ring[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))  # shoelace
    assert area == pytest.approx(math.pi * 0.3**2, rel=1e-12)
    assert v[:, 2].min() == pytest.approx(-0.25) and v[:, 2].max() == pytest.approx(0.25)
    assert len(indices) == 3 * 3 * sides  # two side triangles and one top-cap triangle per edge


def test_faces_point_outwards_and_there_is_no_bottom_cap():
    vertices, indices = prism_mesh(1.0, 2.0, 32)
    v = np.array(vertices)
    for a, b, c in np.array(indices).reshape(-1, 3):
        normal = np.cross(v[b] - v[a], v[c] - v[a])
        centre = (v[a] + v[b] + v[c]) / 3
        assert normal @ centre > 0  # counter-clockwise seen from outside
        assert normal[2] > -1e-9  # nothing faces down: the bottom is open
