"""Sensors by name (clutter_gym.sensors.suite): a sensor is one module plus one registration, an env built with
its name reads it, configs are passed by name with each sensor's registered default when absent, and the fields of
that default are the sensor's nested settings in every env that carries it."""

from __future__ import annotations

import dataclasses
import re

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from clutter_gym import clutter_nav
from clutter_gym.noise.profiles import resolve_noise
from clutter_gym.sensors import SENSORS, ImuConfig, LidarConfig, build_sensors, register_sensor


@dataclasses.dataclass(frozen=True)
class AltimeterConfig:
    """Its settings, which no env declares: the builder takes them from these fields (the mount, ``link``, is the
    robot's, not a setting)."""

    sigma: float = 0.0
    bias: float = 0.0
    link: str = "base_link"

    def __post_init__(self) -> None:
        if not self.sigma >= 0.0:
            raise ValueError(f"altimeter sigma must be >= 0 metres, got {self.sigma!r}")


class Altimeter:
    """A toy sensor that touches nothing shared: the base's height above the floor, with a bias and Gaussian
    noise."""

    name = "altimeter"
    spaces = {"altitude": spaces.Box(-np.inf, np.inf, (1,), np.float32)}
    read_every_step = renders = needs_bodies = False

    def __init__(self, config: AltimeterConfig) -> None:
        self.sigma, self.bias = config.sigma, config.bias

    def reset(self, sim, state, rng):
        pass

    def read(self, sim, state, rng):
        height = float(state.position[2]) + self.bias
        return height + rng.normal(0.0, self.sigma) if self.sigma else height

    def observe(self, reading):
        return {"altitude": np.array([reading], dtype=np.float32)}

    def info(self, reading):
        return {}


@pytest.fixture
def altimeter():
    register_sensor("altimeter", lambda config, noise, robot: Altimeter(config), AltimeterConfig, link=None)
    yield
    del SENSORS["altimeter"]


def test_a_registered_sensor_is_read_by_an_env_that_names_it(make_env, altimeter):
    env = make_env("ClutterFly-v1", sensors=["imu", "altimeter"])
    obs, _ = env.reset(seed=0)
    for _ in range(5):
        obs, *_ = env.step(np.zeros(env.action_space.shape))
    assert obs["altitude"][0] == pytest.approx(env.unwrapped.robot.state().position[2], abs=1e-6)


def test_configs_are_taken_by_name_and_a_missing_one_is_the_registered_default(altimeter):
    imu = ImuConfig(dt=0.05)
    sensors = build_sensors(["lidar", "altimeter", "imu"], resolve_noise("none"),
                            {"lidar": LidarConfig(n_rays=8), "imu": imu}, robot=None)
    assert [s.name for s in sensors] == ["lidar", "altimeter", "imu"]
    assert sensors[0].config.n_rays == 8 and sensors[1].sigma == 0.0 and sensors[2].config is imu
    with pytest.raises(ValueError, match=r"sensor 'imu' has no default config: pass one under configs\['imu'\]"):
        build_sensors(["imu"], resolve_noise("none"), {}, None)
    with pytest.raises(ValueError, match=r"configs for unknown sensors \['sonar'\]"):
        build_sensors(["lidar"], resolve_noise("none"), {"sonar": None}, None)
    with pytest.raises(ValueError, match=r"unknown sensors \['sonar'\]; allowed: \('lidar', 'imu', 'camera', "
                                         r".*'altimeter'\)"):
        build_sensors(["sonar"], resolve_noise("none"), {}, None)
    with pytest.raises(ValueError, match="already registered"):
        register_sensor("lidar", lambda config, noise, robot: None, LidarConfig)


@pytest.mark.parametrize("env_id", ["ClutterNav-v1", "ClutterFly-v1"])
def test_a_registered_sensors_config_fields_are_its_nested_settings(make_env, altimeter, env_id):
    env = make_env(env_id, sensors={"imu": {}, "altimeter": {"bias": 0.25}}).unwrapped
    (imu, altimeter) = env.sensors
    assert (altimeter.sigma, altimeter.bias) == (0.0, 0.25)
    assert make_env(env_id, sensors={"altimeter": {}}).unwrapped.sensors[0].bias == 0.0
    resolved = clutter_nav.SETTINGS.resolve({"sensors": {"altimeter": {"sigma": 0.1, "bias": 1.0}}})
    assert resolved.group("sensors", "altimeter") == {"sigma": 0.1, "bias": 1.0}
    with pytest.raises(TypeError, match=re.escape("unknown setting sensors.altimeter.link; sensors.altimeter takes "
                                                  "['bias', 'sigma']")):
        gym.make(env_id, sensors={"altimeter": {"link": "imu_link"}})
    with pytest.raises(ValueError, match="altimeter sigma must be >= 0 metres, got -1.0"):
        gym.make(env_id, sensors={"altimeter": {"sigma": -1.0}})
