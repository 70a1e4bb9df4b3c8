"""The builder (clutter_gym.builder): an env's settings given flat or nested build the same env, through one alias
table whose every nested place is a field of the part it sets; a nested key the env does not have, or a setting
given both ways, is refused naming it."""

from __future__ import annotations

import dataclasses
import inspect
import math
import re

import gymnasium as gym
import numpy as np
import pytest

import clutter_gym
from clutter_gym import clutter_fly, clutter_nav, clutter_reach
from clutter_gym.builder import ALIASES, nested_path, sensor_configs
from clutter_gym.collision import collision_checker
from clutter_gym.robots.safety import SafetyConfig
from clutter_gym.sensors import LidarConfig, camera_config
from clutter_gym.tasks import FlyRewardWeights, NavRewardWeights, ReachRewardWeights
from clutter_gym.worlds import ClutterSpec, TableSpec

SETTINGS = {"ClutterNav-v1": clutter_nav.SETTINGS, "ClutterReach-v1": clutter_reach.SETTINGS,
            "ClutterFly-v1": clutter_fly.SETTINGS}
#: the settings object each group of each env is made into: its nested names must be that object's
PARTS = {
    ("ClutterNav-v1", "world"): ClutterSpec, ("ClutterReach-v1", "world"): TableSpec,
    ("ClutterFly-v1", "world"): clutter_fly._volume_spec,
    ("ClutterNav-v1", "reward"): NavRewardWeights, ("ClutterReach-v1", "reward"): ReachRewardWeights,
    ("ClutterFly-v1", "reward"): FlyRewardWeights, ("ClutterNav-v1", "safety"): SafetyConfig,
}
#: env id -> (flat settings, the same settings nested), away from every default
SAME_SETTINGS = {
    "ClutterNav-v1": (
        {"sensors": ("lidar", "imu"), "n_rays": 24, "lidar_fov": math.pi, "arena_size": 5.0, "obstacle_density": 0.2,
         "progress_weight": 3.0, "time_weight": 0.02, "safety_horizon": 0.5, "collision_padding": 0.01},
        {"sensors": {"lidar": {"n_rays": 24, "fov": math.pi}, "imu": {}},
         "world": {"arena_size": 5.0, "obstacle_density": 0.2}, "reward": {"progress": 3.0, "time": 0.02},
         "safety": {"horizon": 0.5}, "collision": {"padding": 0.01}}),
    "ClutterReach-v1": (
        {"n_obstacles": 3, "shelf": False, "contact_weight": 2.0, "collision_padding": 0.01, "swept_speed": 0.3},
        {"world": {"n_obstacles": 3, "shelf": False}, "reward": {"contact": 2.0},
         "collision": {"padding": 0.01, "swept_speed": 0.3}}),
    "ClutterFly-v1": (
        {"sensors": ("imu", "lidar"), "n_rays": 12, "lidar_channels": 2, "volume_size": (6.0, 6.0, 3.0),
         "crash_weight": 5.0},
        {"sensors": {"imu": {}, "lidar": {"n_rays": 12, "n_channels": 2}}, "world": {"size": (6.0, 6.0, 3.0)},
         "reward": {"crash": 5.0}}),
}


def rollout(env: gym.Env, steps: int = 8) -> list[np.ndarray]:
    obs, _ = env.reset(seed=4)
    rows = [np.concatenate([np.ravel(obs[k]) for k in sorted(obs)])]
    for action in np.random.default_rng(2).uniform(-1, 1, size=(steps, *env.action_space.shape)):
        obs, reward, terminated, _, info = env.step(action.astype(np.float32))
        rows.append(np.concatenate([np.ravel(obs[k]) for k in sorted(obs)] + [[reward, info["min_clearance"]]]))
        if terminated:
            break
    return rows


@pytest.mark.parametrize("env_id", clutter_gym.ENV_IDS)
def test_flat_and_nested_settings_build_the_same_env(env_id, make_env):
    flat, nested = SAME_SETTINGS[env_id]
    settings = SETTINGS[env_id]
    assert settings.resolve(flat).values == settings.resolve(nested).values
    assert settings.resolve(flat).values != settings.resolve({}).values
    a, b = make_env(env_id, **flat), make_env(env_id, **nested)
    assert a.observation_space == b.observation_space and a.action_space == b.action_space
    for row_a, row_b in zip(rollout(a), rollout(b), strict=True):
        np.testing.assert_array_equal(row_a, row_b)


@pytest.mark.parametrize("env_id", clutter_gym.ENV_IDS)
def test_each_nested_group_holds_the_fields_of_the_part_it_sets(env_id):
    """A nested name is the field or argument of the part's own settings object, so a group is that object's keyword
    arguments; and no two flat names share a place."""
    resolved = SETTINGS[env_id].resolve({})
    for group in SETTINGS[env_id].groups:
        if (env_id, group) in PARTS:
            takes = set(inspect.signature(PARTS[env_id, group]).parameters)
            assert set(resolved.group(group)) <= takes, (group, set(resolved.group(group)) - takes)
    assert set(resolved.group("collision")) <= set(inspect.signature(collision_checker).parameters)
    assert set(resolved.group("sensors", "camera")) <= set(inspect.signature(camera_config).parameters)
    assert set(resolved.group("sensors", "lidar")) <= {f.name for f in dataclasses.fields(LidarConfig)}
    assert len({nested_path(name) for name in resolved.values}) == len(resolved.values)


def test_the_alias_table_holds_only_names_some_env_takes():
    taken = {name for settings in SETTINGS.values() for name in settings.defaults}
    assert set(ALIASES) <= taken, set(ALIASES) - taken
    assert nested_path("self_contact_weight") == ("reward", "self_contact") and nested_path("robot") == ("robot",)


@pytest.mark.parametrize(("nested", "message"), [
    ({"sensors": {"lidar": {"beams": 64}}},
     "unknown setting sensors.lidar.beams; sensors.lidar takes ['caster', 'fov', 'max_range', 'mount_height', "
     "'n_channels', 'n_rays', 'vertical_fov']"),
    ({"reward": {"progres": 1.0}}, "unknown setting reward.progres (did you mean 'progress'?); reward takes ["),
    ({"sensors": {"lidar": {"lidar_fov": 1.0}}}, "unknown setting sensors.lidar.lidar_fov (did you mean 'fov'?)"),
    ({"sensors": {"imu": {"rate": 100}}}, "unknown setting sensors.imu.rate; sensors.imu takes no settings"),
    ({"world": {"arena": {"size": 5.0}}}, "unknown setting world.arena (did you mean 'arena_size'?); world takes ["),
])
def test_an_unknown_nested_key_is_named_with_the_allowed_ones(nested, message):
    with pytest.raises(TypeError, match=re.escape(message)):
        gym.make("ClutterNav-v1", **nested)


@pytest.mark.parametrize(("nested", "message"), [
    ({"reward": 5.0}, "reward must be a mapping of settings by name, got 5.0"),
    ({"sensors": {"lidar": 64}}, "sensors.lidar must be a mapping of settings by name, got 64"),
    ({"sensors": {"sonar": {}}}, "unknown sensors ['sonar']; allowed: ('lidar', 'imu', 'camera', 'odometry')"),
    ({"sensors": {"lidar": {"n_rays": 0}}}, "n_rays must be an integer in [1, 4096]"),  # value errors: flat names
    ({"reward": {"contact": "high"}}, "contact_weight must be a number, got 'high'"),
])
def test_a_bad_nested_value_is_refused(nested, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        gym.make("ClutterNav-v1", **nested)


@pytest.mark.parametrize(("env_id", "given", "message"), [
    ("ClutterNav-v1", {"n_rays": 32, "sensors": {"lidar": {"n_rays": 16}}}, "n_rays and sensors.lidar.n_rays"),
    ("ClutterNav-v1", {"progress_weight": 1.0, "reward": {"progress": 1.0}}, "progress_weight and reward.progress"),
    ("ClutterReach-v1", {"shelf": False, "world": {"shelf": True}}, "shelf and world.shelf"),
    ("ClutterFly-v1", {"volume_size": (5, 5, 3), "world": {"size": (5, 5, 3)}}, "volume_size and world.size"),
])
def test_a_setting_given_flat_and_nested_is_refused(env_id, given, message):
    with pytest.raises(TypeError, match=re.escape(f"{message} are one setting; give it once, flat or nested")):
        gym.make(env_id, **given)


def test_the_nested_sensors_are_the_envs_sensors_in_order(make_env):
    env = make_env("ClutterNav-v1", sensors={"imu": {}, "lidar": {"n_rays": 8}}).unwrapped
    assert [s.name for s in env.sensors] == ["imu", "lidar"] and env.observation_space["lidar"].shape == (8,)
    assert not make_env("ClutterNav-v1", sensors={}).unwrapped.sensors


def test_a_group_of_another_env_is_an_unknown_keyword():
    message = r"ClutterReachEnv got unknown keyword argument\(s\) 'safety'; it takes \[.*'world'"
    with pytest.raises(TypeError, match=message):
        gym.make("ClutterReach-v1", safety={"horizon": 0.3})


@pytest.mark.parametrize("env_id", clutter_gym.ENV_IDS)
def test_the_signature_is_the_settings_then_the_groups(env_id):
    settings = SETTINGS[env_id]
    init = {"ClutterNav-v1": clutter_nav.ClutterNavEnv, "ClutterReach-v1": clutter_reach.ClutterReachEnv,
            "ClutterFly-v1": clutter_fly.ClutterFlyEnv}[env_id]
    parameters = inspect.signature(init).parameters
    assert {name: p.default for name, p in parameters.items() if name in settings.defaults} == dict(settings.defaults)
    assert [name for name in parameters if name not in settings.defaults] == [
        g for g in settings.groups if g != "sensors"]


def test_the_sensor_configs_take_every_lidar_and_camera_setting_and_keep_the_rest():
    s = clutter_nav.SETTINGS.resolve({"sensors": {"lidar": {"n_rays": 90, "fov": 1.0}, "camera": {"size": (32, 24)}},
                                      "camera_modes": ("depth",), "camera_renderer": None})
    configs = sensor_configs(s, sensor_link="sensor_mount")
    lidar, camera, imu = configs["lidar"], configs["camera"], configs["imu"]
    assert (lidar.n_rays, lidar.fov, lidar.n_channels, lidar.link) == (90, 1.0, 1, "sensor_mount")
    assert (camera.width, camera.height, camera.renderer, camera.link) == (32, 24, "rays", "sensor_mount")
    assert imu.dt == pytest.approx(0.05) and imu.link == "imu_link"
    assert math.isclose(lidar.max_range, 3.5)
    with pytest.raises(ValueError, match="camera_size"):
        sensor_configs(clutter_nav.SETTINGS.resolve({"camera_size": 32}))
