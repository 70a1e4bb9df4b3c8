"""Sensors: clean reads of the world (LIDAR, IMU) behind one small protocol."""

from clutter_gym.sensors.base import Sensor
from clutter_gym.sensors.imu import Imu, ImuConfig
from clutter_gym.sensors.lidar import Lidar, LidarConfig

SENSOR_NAMES = ("lidar", "imu")

__all__ = ["SENSOR_NAMES", "Imu", "ImuConfig", "Lidar", "LidarConfig", "Sensor"]
