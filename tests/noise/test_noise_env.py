"""Noise profiles inside the env: clean by default, seeded, timing and actuation as specified."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from helpers import empty_scene

from clutter_gym.noise.profiles import PROFILE_NAMES

DRIVE = np.array([0.6, 0.3], dtype=np.float32)


def rollout(env, seed, steps=12, actions=None):
    obs, info = env.reset(seed=seed)
    out = [(obs, info)]
    for k in range(steps):
        a = DRIVE if actions is None else actions[k]
        obs, _, _, _, info = env.step(a)
        out.append((obs, info))
    return out


def test_noise_none_is_the_clean_env_exactly(make_env):
    clean, none = make_env(), make_env(noise="none")
    for (obs_a, _), (obs_b, _) in zip(rollout(clean, 3), rollout(none, 3)):
        for key in obs_a:
            np.testing.assert_array_equal(obs_a[key], obs_b[key])


@pytest.mark.parametrize("profile", [p for p in PROFILE_NAMES if p != "none"])
def test_a_seed_reproduces_the_noise_bit_for_bit(make_env, profile):
    a, b, c = (make_env(noise=profile, sensors=("lidar", "imu", "camera")) for _ in range(3))
    run_a, run_b, run_c = rollout(a, 5), rollout(b, 5), rollout(c, 6)
    for (obs_a, _), (obs_b, _) in zip(run_a, run_b):
        for key in obs_a:
            np.testing.assert_array_equal(obs_a[key], obs_b[key])
    assert not np.array_equal(run_a[-1][0]["lidar"], run_c[-1][0]["lidar"])


def test_a_seed_gives_the_same_layouts_under_every_profile(make_env):
    scenes = []
    for profile in PROFILE_NAMES:
        env = make_env(noise=profile)
        env.reset(seed=11)
        env.step(DRIVE)
        env.reset()  # the next unseeded layout too
        scenes.append(env.unwrapped.scene.to_dict())
    assert all(scene == scenes[0] for scene in scenes)


def test_profiles_add_noise_of_the_expected_size(make_env):
    """Nominal LIDAR noise on a static scene: per-beam spread ~ range_sigma (10 mm), not zero, not metres."""
    env = make_env(noise={"profile": "nominal", "lidar": {"dropout_prob": 0.0, "spurious_prob": 0.0}})
    env.reset(seed=0, options={"scene": empty_scene()})
    scans = np.array([env.step(np.zeros(2))[4]["lidar_ranges"] for _ in range(40)])
    spread = scans[5:].std(axis=0)  # robot at rest after a few steps; the bias is constant within the episode
    assert 0.006 < np.median(spread) < 0.014


def test_lidar_rate_holds_readings_between_updates(make_env):
    env = make_env(noise={"lidar": {"rate_hz": 5.0}})  # 20 Hz control: a new scan every 4 steps
    run = rollout(env, seed=2, steps=16)
    scans = [info["lidar_ranges"] for _, info in run]
    changes = [k for k in range(1, len(scans)) if not np.array_equal(scans[k], scans[k - 1])]
    assert all(b - a == 4 for a, b in zip(changes, changes[1:])) and len(changes) >= 3


def test_latency_delays_readings_by_whole_steps(make_env):
    fresh = rollout(make_env(), seed=4, steps=10)
    late = rollout(make_env(noise={"lidar": {"latency_steps": 2}, "imu": {"latency_steps": 1}}), seed=4, steps=10)
    for k in range(2, 11):
        np.testing.assert_array_equal(late[k][0]["lidar"], fresh[k - 2][0]["lidar"])
        np.testing.assert_array_equal(late[k][0]["imu"], fresh[k - 1][0]["imu"])
    np.testing.assert_array_equal(late[1][0]["lidar"], fresh[0][0]["lidar"])  # the first reading fills the line


def test_action_latency_shifts_the_commands(make_env):
    actions = np.random.default_rng(0).uniform(-1, 1, (10, 2)).astype(np.float32)
    shifted = np.vstack([np.zeros((1, 2), np.float32), actions[:-1]])
    late = rollout(make_env(noise={"action": {"latency_steps": 1}}), seed=8, steps=10, actions=actions)
    direct = rollout(make_env(), seed=8, steps=10, actions=shifted)
    for (obs_a, _), (obs_b, _) in zip(late, direct):
        np.testing.assert_array_equal(obs_a["velocity"], obs_b["velocity"])


def test_dynamics_randomisation_changes_the_robot_each_episode_and_only_then(make_env):
    env = make_env(noise={"dynamics": {"mass_range": 0.3, "friction_range": 0.3, "motor_range": 0.3}})
    robot = env.unwrapped.robot
    masses = set()
    for seed in range(4):
        env.reset(seed=seed)
        mass, friction, _ = env.unwrapped.sim.actuation.inertial_properties(robot.body, [-1])[0]
        nominal_mass, nominal_friction, _ = robot._nominal[-1]
        assert 0.7 * nominal_mass <= mass <= 1.3 * nominal_mass
        assert 0.7 * nominal_friction <= friction <= 1.3 * nominal_friction
        masses.add(round(mass, 9))
    assert len(masses) == 4
    clean = make_env()
    clean.reset(seed=0)
    inertial = clean.unwrapped.sim.actuation.inertial_properties(clean.unwrapped.robot.body, [-1])
    assert inertial[0][0] == robot._nominal[-1][0]


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_check_env_passes_with_harsh_noise_and_a_camera(make_env):
    env = make_env(noise="harsh", sensors=("lidar", "imu", "camera"), camera_modes=("rgb", "depth", "segmentation"))
    check_env(env.unwrapped, skip_render_check=True)


def test_observation_space_is_the_same_under_every_profile(make_env):
    spaces = {p: make_env(noise=p, sensors=("lidar", "imu", "camera")).observation_space for p in PROFILE_NAMES}
    assert all(space == spaces["none"] for space in spaces.values())


def test_inf_no_return_reaches_info_but_not_the_observation(make_env):
    env = make_env(noise={"lidar": {"no_return": "inf", "dropout_prob": 0.5}})
    obs, info = env.reset(seed=1)
    assert np.isinf(info["lidar_ranges"]).any()
    np.testing.assert_array_equal(obs["lidar"][np.isinf(info["lidar_ranges"])], 1.0)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"noise": "noisy"}, r"noise profile must be one of"),
        ({"noise": {"lidar": {"range_sigma": -1}}}, r"lidar\.range_sigma must be a number in \[0\.0, 1\.0\] m"),
        ({"camera_size": (4, 84)}, r"camera_size\[0\] \(width\) must be an integer in \[8, 1024\]"),
        ({"camera_modes": ("rgb", "thermal")}, r"camera_modes must be a non-empty tuple of names"),
        ({"camera_renderer": "vulkan"}, r"camera_renderer must be one of \('tiny', 'egl', 'rays'\)"),
        ({"lidar_channels": 0}, r"lidar_channels must be an integer in \[1, 128\]"),
    ],
)
def test_bad_noise_and_camera_kwargs_raise_at_make(make_env, kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        make_env(**kwargs)
