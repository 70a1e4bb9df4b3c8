"""The sensor configs of ClutterNav and ClutterFly come from their keyword arguments through one alias table
(clutter_gym.sensors.settings): no sensor argument of either env is left out of it, and each reaches its field."""

from __future__ import annotations

import inspect
import math

import pytest

from clutter_gym.clutter_fly import ClutterFlyEnv
from clutter_gym.clutter_nav import ClutterNavEnv
from clutter_gym.sensors.settings import SENSOR_ARGUMENTS, sensor_configs


@pytest.mark.parametrize("env_class", [ClutterNavEnv, ClutterFlyEnv])
def test_every_sensor_argument_of_the_env_is_in_the_table(env_class):
    names = [n for n in inspect.signature(env_class.__init__).parameters
             if n.startswith(("lidar_", "camera_")) or n == "n_rays"]
    assert names and all(n in SENSOR_ARGUMENTS for n in names), [n for n in names if n not in SENSOR_ARGUMENTS]


def test_each_argument_reaches_its_field_and_the_rest_keep_their_defaults():
    configs = sensor_configs({"n_rays": 90, "lidar_fov": 1.0, "camera_size": (32, 24), "camera_modes": ("depth",),
                              "camera_fov": 1.0, "camera_far": 5.0, "camera_renderer": None, "unrelated": 3},
                             control_hz=20.0, sensor_link="sensor_mount")
    lidar, camera, imu = configs["lidar"], configs["camera"], configs["imu"]
    assert (lidar.n_rays, lidar.fov, lidar.n_channels, lidar.link) == (90, 1.0, 1, "sensor_mount")
    assert (camera.width, camera.height, camera.renderer, camera.link) == (32, 24, "rays", "sensor_mount")
    assert imu.dt == pytest.approx(0.05) and imu.link == "imu_link"
    assert math.isclose(lidar.max_range, 3.5)


def test_a_bad_camera_size_is_named():
    with pytest.raises(ValueError, match="camera_size"):
        sensor_configs({"camera_size": 32, "camera_modes": ("depth",), "camera_fov": 1.0, "camera_far": 5.0,
                        "camera_renderer": None}, control_hz=20.0)
