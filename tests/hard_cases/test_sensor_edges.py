"""Sensors at the edge of their range: the camera's far plane at its limits, a LIDAR beam with nothing to hit and
beams starting inside an obstacle, the IMU through a full-speed impact.

Tolerances: at ``camera_far`` = 1000 m the 24-bit depth buffer resolves about d^2 / near * 2^-24 = 1e-5 m at the
wall's 2.8 m, so depth is held to 0.1 mm; the IMU reports the mean acceleration over a control period, so a stop
from full speed within one period reads max_linear_speed * control_hz.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.hard_cases.scenes.sensor_edges import OBSTACLE, WALL_DEPTH, imu_impact, wall_view
from clutter_gym.sim import Sim


@pytest.mark.parametrize("far", [10.0, 1000.0])
def test_wall_depth_holds_up_to_the_largest_far_plane(make_env, far):
    depth, segmentation = wall_view(make_env, far)
    wall = segmentation == OBSTACLE
    assert wall.sum() > 500
    np.testing.assert_allclose(depth[wall], WALL_DEPTH, atol=1e-4)


@pytest.mark.parametrize("far", [0.1, WALL_DEPTH - 0.01])
def test_nothing_beyond_the_far_plane_is_seen(make_env, far):
    depth, segmentation = wall_view(make_env, far)
    assert not (segmentation == OBSTACLE).any()
    assert np.isfinite(depth).all() and depth.max() <= far
    assert (depth == 0.0).sum() > depth.size // 3  # the sky and the wall read "no data"


def test_beams_that_hit_nothing_or_start_inside_an_obstacle():
    """Nothing to hit reads no hit (the LIDAR's max range). A beam starting inside a box misses it (Bullet's convex
    ray test), one starting inside a cylinder meets its wall from within (a triangle mesh has no inside): neither
    occurs in the envs, whose beams start 0.12 m from the mount, inside the robot's footprint."""
    sim = Sim()
    try:
        sim.obstacles.add_static_boxes((0.5, 0.5, 0.5), (1, 0, 0, 1), [(0.0, 0.0, 0.5)])
        sim.obstacles.add_static_cylinders(0.5, 1.0, (0, 1, 0, 1), [(5.0, 0.0, 0.5)])
        starts = [[0, 3, 0.5], [0, 0, 0.5], [5, 0, 0.5], [-2, 0, 0.5]]
        ends = [[4, 3, 0.5], [2, 0, 0.5], [7, 0, 0.5], [2, 0, 0.5]]
        nothing, in_box, in_cylinder, outside = sim.rays.ray_hit_fractions(starts, ends)
    finally:
        sim.close()
    assert nothing == 1.0 and in_box == 1.0
    assert outside == pytest.approx(1.5 / 4.0)  # the box's face at x = -0.5
    assert 2.0 * in_cylinder == pytest.approx(0.5, abs=2e-3)  # the prism's wall, 0.5 m out (its area's radius)


@pytest.mark.parametrize("accel_range", [None, 5.0])
def test_imu_through_a_full_speed_impact_is_finite_and_saturates(make_env, accel_range):
    readings, contacts, _ = imu_impact(make_env, accel_range)  # 0.3 m from the wall, facing it, at full command
    assert contacts and np.isfinite(readings).all()
    peak = np.abs(readings[:, 0]).max()
    if accel_range is None:  # 0.5 m/s to 0 within one 0.05 s control period
        assert peak == pytest.approx(0.5 * 20.0, rel=0.05)
    else:
        assert peak == accel_range and np.abs(readings[:, :3]).max() <= accel_range
