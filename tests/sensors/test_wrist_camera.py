"""ClutterReach-v1's wrist camera: a depth camera on the end effector looking along the hand's approach axis,
checked against the analytic depth of the table and of a box under the hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.robots.panda import READY
from clutter_gym.worlds.table.spec import TABLE_GAP

TARGET = [0.5, 0.3, 0.2]


def _centre_depth(env, obstacles):
    obs, _ = env.reset(seed=0, options={"scene": {"obstacles": obstacles, "start": list(READY), "target": TARGET}})
    state = env.unwrapped.robot.state()
    ee = state.links.position[state.link("panda_grasptarget")]
    axis = state.links.rotation[state.link("panda_grasptarget")][:, 2]
    depth = obs["camera_depth"]
    h, w = depth.shape
    return float(depth[h // 2 - 1:h // 2 + 1, w // 2 - 1:w // 2 + 1].mean()), ee, axis


def test_the_wrist_camera_sees_the_table_at_the_hands_height_when_the_hand_points_down(make_env):
    """In the ready pose the hand points straight down: along the optical axis the table top lies at the end
    effector's height above it (the four central pixels straddle the axis; at 32 px and 58 degrees they are 0.9
    degrees off it, so depth along the axis differs by far less than a millimetre)."""
    env = make_env("ClutterReach-v1", sensors=("camera",), shelf=False)
    depth, ee, axis = _centre_depth(env, [])
    np.testing.assert_allclose(axis, [0.0, 0.0, -1.0], atol=1e-3)
    assert depth == pytest.approx(ee[2] + TABLE_GAP, abs=1e-3)


def test_a_box_under_the_hand_comes_closer_by_its_height(make_env):
    env = make_env("ClutterReach-v1", sensors=("camera",), shelf=False)
    _, ee, _ = _centre_depth(env, [])
    box = {"shape": "box", "position": [float(ee[0]), float(ee[1])], "size": [0.1, 0.1, 0.2]}
    depth, ee, _ = _centre_depth(env, [box])
    assert depth == pytest.approx(ee[2] - 0.2, abs=1e-3)  # clutter stands on z = 0, TABLE_GAP above the table top


def test_the_camera_is_off_by_default_and_refused_where_it_does_not_fit(make_env):
    assert "camera_depth" not in make_env("ClutterReach-v1").observation_space.spaces
    with pytest.raises(ValueError, match=r"sensors must be \(\) or \('camera',\)"):
        make_env("ClutterReach-v1", sensors=("lidar",))
    with pytest.raises(ValueError, match="camera_renderer='rays' draws only"):
        make_env("ClutterReach-v1", sensors=("camera",), camera_modes=("rgb",))
    assert math.isclose(make_env("ClutterReach-v1", sensors=("camera",)).observation_space["camera_depth"].high.max(),
                        2.0)
