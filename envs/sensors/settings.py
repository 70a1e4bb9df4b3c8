"""The sensor configs of an env from its flat keyword arguments, through one alias table: each ``gym.make`` argument
that sets a sensor names the sensor and the config field it sets. ClutterNav and ClutterFly build their LIDAR, IMU
and camera here; an env passes only the arguments it has, and the config's own default stands for the rest."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from clutter_gym.sensors.camera import CameraConfig, camera_config
from clutter_gym.sensors.imu import ImuConfig
from clutter_gym.sensors.lidar import LidarConfig

#: env keyword argument -> (sensor, its config field); the camera's fields are :func:`camera_config`'s arguments
SENSOR_ARGUMENTS = {
    "n_rays": ("lidar", "n_rays"), "lidar_fov": ("lidar", "fov"), "lidar_range": ("lidar", "max_range"),
    "lidar_mount_height": ("lidar", "mount_height"), "lidar_channels": ("lidar", "n_channels"),
    "lidar_vertical_fov": ("lidar", "vertical_fov"), "lidar_caster": ("lidar", "caster"),
    "camera_size": ("camera", "size"), "camera_modes": ("camera", "modes"), "camera_fov": ("camera", "fov"),
    "camera_far": ("camera", "far"), "camera_renderer": ("camera", "renderer"),
}


def sensor_configs(arguments: Mapping[str, Any], control_hz: float, sensor_link: str | None = None,
                   imu_link: str | None = None) -> dict[str, Any]:
    """The configs by sensor name (``lidar``, ``imu``, ``camera``) of an env's keyword ``arguments`` (its
    ``locals()``: the names of :data:`SENSOR_ARGUMENTS` it has are read, the rest ignored). ``sensor_link`` mounts
    the LIDAR and the camera, ``imu_link`` the IMU, where the robot's links differ from the configs' defaults.

    Raises:
        ValueError: a value out of its config's range, naming the argument where :func:`camera_config` checks it.
    """
    grouped: dict[str, dict[str, Any]] = {"lidar": {}, "camera": {}}
    for argument, (sensor, field) in SENSOR_ARGUMENTS.items():
        if argument in arguments:
            grouped[sensor][field] = arguments[argument]
    camera = grouped["camera"]
    lidar = LidarConfig(**grouped["lidar"])
    imu = ImuConfig(dt=1.0 / control_hz)
    mounted = CameraConfig()
    if camera:
        mounted = camera_config(camera["size"], camera["modes"], camera["fov"], camera["far"], camera["renderer"])
    if sensor_link is not None:
        lidar, mounted = replace(lidar, link=sensor_link), replace(mounted, link=sensor_link)
    if imu_link is not None:
        imu = replace(imu, link=imu_link)
    return {"lidar": lidar, "imu": imu, "camera": mounted}
