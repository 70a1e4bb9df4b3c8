"""The sensor set of an env, built from its ``sensors=(...)`` names, geometry kwargs and noise profile."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from clutter_gym.interfaces import Sensor
from clutter_gym.noise.profiles import NoiseProfile
from clutter_gym.sensors.camera import Camera, CameraConfig
from clutter_gym.sensors.imu import Imu, ImuConfig
from clutter_gym.sensors.lidar import Lidar, LidarConfig

SENSOR_NAMES = ("lidar", "imu", "camera")


def check_sensor_names(sensors: Sequence[str]) -> tuple[str, ...]:
    """The ``sensors`` kwarg as a tuple, or a ValueError naming the allowed sensors."""
    if isinstance(sensors, str) or not isinstance(sensors, Sequence):
        raise ValueError(f"sensors must be a tuple of names from {SENSOR_NAMES}, got {sensors!r}")
    unknown = [s for s in sensors if s not in SENSOR_NAMES]
    if unknown:
        raise ValueError(f"unknown sensors {unknown}; allowed: {SENSOR_NAMES}")
    if len(set(sensors)) != len(sensors):
        raise ValueError(f"sensors must not repeat a name, got {tuple(sensors)}")
    return tuple(sensors)


def build_sensors(
    names: Sequence[str], noise: NoiseProfile, lidar: LidarConfig, imu: ImuConfig, camera: CameraConfig
) -> list[Sensor]:
    """One sensor per name, in order, each with its noise from the profile."""
    factories: dict[str, Callable[[], Sensor]] = {  # typed: mypy holds each sensor to the Sensor protocol
        "lidar": lambda: Lidar(lidar, noise.lidar),
        "imu": lambda: Imu(imu, noise.imu),
        "camera": lambda: Camera(camera, noise.camera_rgb, noise.camera_depth),
    }
    return [factories[name]() for name in check_sensor_names(names)]
