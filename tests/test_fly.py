"""ClutterFly-v1 as a whole env: hover, contact and crash, leaving the volume, the progress sign, the floor as an
obstacle, kwargs and scene errors, user scenes, and every noise profile with every sensor."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.training.baselines import CascadedFlyer

SIZE = (4.0, 4.0, 2.0)  # a small volume: cheap path distances
FULL_THRUST = np.array([1.0, 0.0, 0.0, 0.0])


def fly_env(make_env, **kwargs):
    return make_env("ClutterFly-v1", volume_size=SIZE, **kwargs)


def scene(obstacles=(), start=(0.0, 0.0, 1.0, 0.0), goal=(1.5, 1.5, 1.0)):
    return {"obstacles": list(obstacles), "start": list(start), "goal": list(goal)}


def hover(env) -> np.ndarray:
    return env.unwrapped.robot.hover_action(env.unwrapped.sim.gravity)


def test_hover_from_reset_holds_position_and_attitude_for_two_seconds(make_env):
    env = fly_env(make_env)
    env.reset(options={"scene": scene()})
    action = hover(env)
    for _ in range(60):  # 2 s at 30 Hz
        obs, reward, terminated, truncated, info = env.step(action)
        assert not terminated and info["cost"] == 0.0
    state = env.unwrapped.robot.state()
    assert np.abs(np.asarray(state.position) - (0.0, 0.0, 1.0)).max() < 1e-3  # metres
    assert state.rotation[2, 2] > 1.0 - 1e-6
    np.testing.assert_allclose(obs["imu"], [0.0, 0.0, 9.81, 0.0, 0.0, 0.0], atol=1e-3)
    np.testing.assert_allclose(obs["attitude"], [0.0, 0.0, 1.0], atol=1e-6)
    assert info["reward_terms"]["control"] == 0.0  # the hover action costs nothing


def test_flying_into_an_obstacle_is_a_contact_that_costs_and_ends_the_episode(make_env):
    slab = {"shape": "box", "size": [1.0, 1.0, 0.1], "position": [0.0, 0.0], "z": 1.3}
    env = fly_env(make_env, terminate_on_collision=True)
    env.reset(options={"scene": scene([slab])})
    for step in range(60):
        obs, reward, terminated, truncated, info = env.step(FULL_THRUST)
        if terminated:
            break
    assert terminated and step > 0
    assert info["n_contacts"] > 0 and info["cost"] == 1.0 and not info["is_success"]
    assert info["reward_terms"]["contact"] < 0.0 and info["reward_terms"]["crash"] < 0.0
    assert info["closest_pair"][1] == 0  # the slab, the scene's first obstacle


def test_without_terminate_on_collision_a_contact_costs_but_the_episode_goes_on(make_env):
    slab = {"shape": "box", "size": [1.0, 1.0, 0.1], "position": [0.0, 0.0], "z": 1.3}
    env = fly_env(make_env)
    env.reset(options={"scene": scene([slab])})
    costs = [env.step(FULL_THRUST)[4]["cost"] for _ in range(30)]
    assert max(costs) == 1.0
    assert not env.step(FULL_THRUST)[2]


def test_falling_onto_the_floor_is_a_contact_both_engines_see(make_env):
    env = fly_env(make_env, terminate_on_collision=True)
    env.reset(options={"scene": scene(start=(0.0, 0.0, 0.3, 0.0))})
    for _ in range(60):
        obs, reward, terminated, truncated, info = env.step(-FULL_THRUST)  # rotors stop
        if terminated:
            break
    assert terminated and info["cost"] == 1.0
    assert info["pybullet_contacts"] > 0 and not info["contact_disagreement"]


def test_leaving_the_volume_over_the_top_terminates(make_env):
    env = fly_env(make_env, ceiling=False)
    env.reset(options={"scene": scene()})
    for _ in range(90):
        obs, reward, terminated, truncated, info = env.step(FULL_THRUST)
        if terminated:
            break
    assert terminated and not info["is_success"] and info["cost"] == 0.0
    assert env.unwrapped.robot.state().position[2] > SIZE[2]
    assert info["reward_terms"]["crash"] == -10.0


def test_flipping_terminates(make_env):
    env = fly_env(make_env, max_tilt=math.radians(30))
    env.reset(options={"scene": scene()})
    action = hover(env)
    action[1] = 1.0  # roll at 3 rad/s
    for step in range(30):
        terminated = env.step(action)[2]
        if terminated:
            break
    tilt = math.acos(env.unwrapped.robot.state().rotation[2, 2])
    assert terminated and math.radians(30) < tilt < math.radians(60)


@pytest.mark.parametrize("thrust", [0.3, -0.3])
def test_progress_has_the_sign_of_motion_towards_the_goal(make_env, thrust):
    """Goal straight above in open space, both on a column of grid cell centres (where the path distance is the
    straight line, as every grid step up the column is certified): each step's progress is 10 x the height gained,
    positive climbing and negative sinking."""
    env = fly_env(make_env)
    env.reset(options={"scene": scene(start=(0.1, 0.1, 0.7, 0.0), goal=(0.1, 0.1, 1.5))})
    action = hover(env)
    action[0] += thrust
    heights, progress = [env.unwrapped.robot.state().position[2]], []
    for _ in range(8):
        progress.append(env.step(action)[4]["reward_terms"]["progress"])
        heights.append(env.unwrapped.robot.state().position[2])
    np.testing.assert_allclose(progress, 10.0 * np.diff(heights), rtol=1e-9, atol=1e-12)
    assert (min(progress) > 0.0) if thrust > 0 else (max(progress) < 0.0)


def test_progress_follows_the_path_round_an_obstacle(make_env):
    """Goal straight above behind a slab: the progress is the decrease of the path round the slab, not of the
    straight distance, and climbing towards the slab still shortens that path."""
    slab = {"shape": "box", "size": [1.0, 1.0, 0.1], "position": [0.0, 0.0], "z": 1.3}
    env = fly_env(make_env)
    env.reset(options={"scene": scene([slab], start=(0.0, 0.0, 0.8, 0.0), goal=(0.0, 0.0, 1.7))})
    task = env.unwrapped.task
    before = task.path_distance(env.unwrapped.robot.state())
    assert before > 0.9 + 1.0  # out past the slab's edge and back
    action = hover(env)
    action[0] += 0.3
    progress = [env.step(action)[4]["reward_terms"]["progress"] for _ in range(8)]
    after = task.path_distance(env.unwrapped.robot.state())
    assert sum(progress) == pytest.approx(10.0 * (before - after)) and sum(progress) > 0.0


def test_reaching_the_goal_is_success(make_env):
    env = fly_env(make_env)
    env.reset(options={"scene": scene(goal=(0.0, 0.0, 1.5))})
    for _ in range(60):
        obs, reward, terminated, truncated, info = env.step(hover(env) + np.array([0.2, 0, 0, 0]))
        if terminated:
            break
    assert terminated and info["is_success"] and info["reward_terms"]["success"] == 10.0


def test_goal_observation_is_the_body_frame_vector_and_its_length(make_env):
    env = fly_env(make_env)
    obs, _ = env.reset(options={"scene": scene(start=(0.0, 0.0, 1.0, math.pi / 2), goal=(1.0, 0.0, 1.5))})
    # yawed 90 degrees left: world +x is the body's -y
    np.testing.assert_allclose(obs["goal"], [0.0, -1.0, 0.5, math.sqrt(1.25)], atol=1e-6)


def test_the_subgoal_is_the_waypoint_ahead_on_the_path_in_the_body_frame(make_env):
    env = fly_env(make_env, subgoal_lookahead=0.5)
    pole = {"shape": "cylinder", "radius": 0.3, "height": 2.0, "position": [0.75, 0.75]}
    obs, _ = env.reset(options={"scene": scene([pole], start=(0.0, 0.0, 1.0, 0.7))})
    task, state = env.unwrapped.task, env.unwrapped.robot.state()
    path = task.planned_path(state.position)
    point = np.asarray(state.position) + state.rotation @ obs["subgoal"]
    np.testing.assert_allclose(point, task._path_distance.waypoint(*state.position, lookahead=0.5), atol=1e-6)
    distances = np.linalg.norm(path[:, None, :] - point, axis=2).min()
    assert distances < 0.2  # on the path, within one segment of a listed point (0.2 m cells)
    assert np.linalg.norm(obs["subgoal"]) <= 0.5 + 1e-6
    assert env.observation_space["subgoal"].contains(obs["subgoal"])
    assert "subgoal" not in fly_env(make_env).observation_space.spaces


@pytest.mark.parametrize("value", [-0.1, 100.0, math.nan])
def test_subgoal_lookahead_out_of_range_is_refused(make_env, value):
    with pytest.raises(ValueError, match=r"subgoal_lookahead must be in \[0, 6(\.\d+)?\] metres"):
        fly_env(make_env, subgoal_lookahead=value)


def test_a_user_scene_round_trips(make_env):
    env = fly_env(make_env)
    pole = {"shape": "cylinder", "radius": 0.2, "height": 2.0, "position": [1.0, -1.0]}
    beam = {"shape": "box", "size": [2.0, 0.1, 0.1], "position": [-1.0, 1.0], "yaw": 0.3, "z": 1.2}
    given = scene([pole, beam], start=(-1.0, -1.0, 0.5, 0.2), goal=(1.2, 1.2, 1.5))
    first, _ = env.reset(options={"scene": given})
    out = env.unwrapped.scene.to_dict()
    assert out["start"] == given["start"] and out["goal"] == given["goal"]
    assert out["obstacles"][0] == pole and out["obstacles"][1] == {**beam}
    again, _ = env.reset(options={"scene": out})
    for key in first:
        np.testing.assert_array_equal(first[key], again[key])


def test_a_generated_scene_round_trips_through_reset_options(make_env):
    a, b = make_env("ClutterFly-v1"), make_env("ClutterFly-v1")
    obs_a, _ = a.reset(seed=4)
    obs_b, _ = b.reset(seed=99, options={"scene": a.unwrapped.scene.to_dict()})
    assert b.unwrapped.scene == a.unwrapped.scene
    rng = np.random.default_rng(0)
    for _ in range(5):
        action = rng.uniform(-1, 1, 4)
        step_a, step_b = a.step(action), b.step(action)
        np.testing.assert_array_equal(step_a[0]["goal"], step_b[0]["goal"])
        assert step_a[1] == step_b[1]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"volume_size": (1.0, 4.0, 2.0)}, "volume_size x must be in"),
        ({"volume_size": (4.0, 4.0, 0.5)}, r"volume_size z must be in \[1, 5\]"),
        ({"volume_size": "big"}, "volume_size must be 3 finite numbers"),
        ({"obstacle_density": 0.5}, r"obstacle_density must be a number in \[0, 0.25\]"),
        ({"obstacle_density": "dense"}, "obstacle_density must be a number"),
        ({"ceiling": "no"}, "ceiling must be True or False"),
        ({"sensors": ("imu", "sonar")}, "unknown sensors"),
        ({"sensors": "imu"}, "sensors must be a tuple"),
        ({"n_rays": 0}, r"n_rays must be an integer in \[1, 4096\]"),
        ({"lidar_channels": 200}, "lidar_channels must be an integer"),
        ({"lidar_vertical_fov": 2.0}, "lidar_vertical_fov must be in"),
        ({"camera_modes": ("depth", "infrared")}, "camera_modes must be"),
        ({"camera_size": (4, 4)}, "camera_size"),
        ({"max_tilt": 0.0}, r"max_tilt must be in \(0, pi\]"),
        ({"success_radius": -1.0}, "success_radius must be in"),
        ({"clearance_margin": 2.0}, "clearance_margin must be in"),
        ({"aero": ("lift",)}, "aero must be"),
        ({"aero": "drag"}, "aero must be"),
        ({"swept_speed": 0.0}, "swept_speed must be > 0"),
        ({"crash_weight": -1.0}, "reward weight crash must be in"),
        ({"attitude_weight": math.nan}, "reward weight attitude must be in"),
        ({"control_hz": 7.0}, "physics_hz must be an integer multiple of control_hz"),
        ({"collision_fidelity": "exact"}, "collision_fidelity must be one of"),
        ({"collision_padding": 2.0}, "padding"),
        ({"terminate_on_collision": 1}, "terminate_on_collision must be True or False"),
        ({"noise": "foggy"}, "foggy"),
    ],
)
def test_bad_kwargs_name_the_field(make_env, kwargs, message):
    with pytest.raises(ValueError, match=message):
        make_env("ClutterFly-v1", **kwargs)


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"start": [0.0, 0.0, 0.03, 0.0]}, r"scene.start .* the robot needs at least its radius"),
        ({"goal": [0.0, 0.0, 3.0]}, "scene.goal must lie inside the volume"),
        ({"start": [0.0, 0.0, 1.0]}, "scene.start must be a list of 4 numbers"),
        ({"obstacles": [{"shape": "box", "size": [1, 1, 1], "position": [9.0, 0.0]}]}, r"scene.obstacles\[0\]"),
    ],
)
def test_bad_scene_fields_are_named(make_env, bad, message):
    env = fly_env(make_env)
    with pytest.raises(ValueError, match=message):
        env.reset(options={"scene": {**scene(), **bad}})


@pytest.mark.parametrize(("action", "message"), [([np.nan, 0, 0, 0], "finite"), ([0.0, 0.0], "shape")])
def test_bad_actions_name_the_action(make_env, action, message):
    env = fly_env(make_env)
    env.reset(options={"scene": scene()})
    with pytest.raises(ValueError, match=message):
        env.step(np.array(action))


@pytest.mark.parametrize("profile", PROFILE_NAMES)
def test_every_noise_profile_applies_to_every_sensor(make_env, profile):
    sensors = ("imu", "lidar", "camera")
    kwargs = dict(sensors=sensors, n_rays=16, lidar_channels=4, camera_size=(16, 16), camera_modes=("depth", "rgb"))
    clean, noisy = fly_env(make_env, **kwargs), fly_env(make_env, noise=profile, **kwargs)
    assert noisy.unwrapped.noise.name == profile
    readings = []
    for env in (clean, noisy):
        env.reset(seed=1, options={"scene": scene([{"shape": "cylinder", "radius": 0.3, "height": 2.0,
                                                     "position": [1.0, 0.0]}])})
        rows = [env.step(hover(env))[0] for _ in range(6)]
        assert all(env.observation_space.contains(obs) for obs in rows)
        readings.append(rows[-1])
    differs = {key: not np.array_equal(readings[0][key], readings[1][key]) for key in ("imu", "lidar", "camera_depth")}
    assert all(differs.values()) == (profile != "none"), differs


def test_the_cascaded_flyer_on_the_subgoal_flies_seeded_layouts_without_contact(make_env):
    """The map-based planner reference: a position controller on the planned path's subgoal reaches the goal of
    every one of five seeded layouts of the small volume, touching nothing; aimed at the goal itself (mapless) in
    an empty volume it reaches it too."""
    env = fly_env(make_env, subgoal_lookahead=0.5, obstacle_density=0.08)
    flyer = CascadedFlyer.for_env(env, "subgoal")
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        done, cost = False, 0.0
        while not done:
            obs, _, terminated, truncated, info = env.step(flyer(obs))
            done, cost = terminated or truncated, max(cost, info["cost"])
        assert info["is_success"] and cost == 0.0, seed
    open_env = fly_env(make_env, obstacle_density=0.0)
    mapless = CascadedFlyer.for_env(open_env)
    obs, _ = open_env.reset(seed=0)
    for _ in range(300):
        obs, _, terminated, truncated, info = open_env.step(mapless(obs))
        if terminated:
            break
    assert info["is_success"]
    with pytest.raises(ValueError, match="has no 'subgoal' observation"):
        CascadedFlyer.for_env(open_env, "subgoal")
