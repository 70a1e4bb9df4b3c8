"""Sensors: clean reads of the world (LIDAR, IMU, camera), each followed by its noise chain."""

from clutter_gym.interfaces import Sensor
from clutter_gym.sensors.camera import SEGMENTATION_CLASSES, Camera, CameraConfig, camera_config
from clutter_gym.sensors.imu import Imu, ImuConfig
from clutter_gym.sensors.lidar import Lidar, LidarConfig
from clutter_gym.sensors.suite import SENSOR_NAMES, build_sensors, check_sensor_names

__all__ = [
    "SEGMENTATION_CLASSES",
    "SENSOR_NAMES",
    "Camera",
    "CameraConfig",
    "Imu",
    "ImuConfig",
    "Lidar",
    "LidarConfig",
    "Sensor",
    "build_sensors",
    "camera_config",
    "check_sensor_names",
]
