"""Sensors: clean reads of the world (LIDAR, IMU, camera, wheel odometry), each followed by its noise chain,
registered by name (:mod:`clutter_gym.sensors.suite`)."""

from clutter_gym.interfaces import Sensor
from clutter_gym.sensors.camera import SEGMENTATION_CLASSES, Camera, CameraConfig, camera_config
from clutter_gym.sensors.imu import Imu, ImuConfig
from clutter_gym.sensors.lidar import Lidar, LidarConfig
from clutter_gym.sensors.odometry import WheelOdometry
from clutter_gym.sensors.suite import SENSORS, build_sensors, check_sensor_names, register_sensor, sensor_links

register_sensor("lidar", lambda config, noise, robot: Lidar(config, noise.lidar), LidarConfig,
                observation=Lidar.observation)
register_sensor("imu", lambda config, noise, robot: Imu(config, noise.imu), None,  # its config needs the control rate
                observation=Imu.observation)
register_sensor("camera", lambda config, noise, robot: Camera(config, noise.camera_rgb, noise.camera_depth),
                CameraConfig, observation=Camera.observation)
register_sensor("odometry", lambda config, noise, robot: WheelOdometry(robot, noise.section("odometry")),
                lambda: None, link=None, observation=WheelOdometry.observation)  # reads the wheels: no config, no mount

__all__ = [
    "SEGMENTATION_CLASSES",
    "SENSORS",
    "Camera",
    "CameraConfig",
    "Imu",
    "ImuConfig",
    "Lidar",
    "LidarConfig",
    "Sensor",
    "WheelOdometry",
    "build_sensors",
    "camera_config",
    "check_sensor_names",
    "register_sensor",
    "sensor_links",
]
