"""The residual policy on a base controller (ClutterNav's potential field, ClutterReach's and ClutterFly's subgoal
pursuits, ClutterReach's proximity field and ClutterFly's flyer on the goal): the wrapper and a loaded agent add the
same term."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import SHELF_SEED

from clutter_gym.training import load
from clutter_gym.training.baselines import CascadedFlyer, PotentialFieldNavigator, ProximityFieldReacher
from clutter_gym.training.config import config_for
from clutter_gym.training.residual import SubgoalResidual, residual_action, subgoal_pursuit
from clutter_gym.training.train import start, train


def test_the_wrapper_steps_the_env_with_pursuit_plus_residual(make_env):
    plain = make_env("ClutterReach-v1", subgoal_lookahead=0.2)
    wrapped = SubgoalResidual(make_env("ClutterReach-v1", subgoal_lookahead=0.2), gain=15.0)
    obs, _ = plain.reset(seed=SHELF_SEED)
    same, _ = wrapped.reset(seed=SHELF_SEED)
    residual = np.full(7, 0.1, dtype=np.float32)
    expected = np.clip(np.clip(15.0 * obs["subgoal"], -1.0, 1.0) + residual, -1.0, 1.0)
    np.testing.assert_allclose(residual_action(obs, residual, subgoal_pursuit("ClutterReach-v1", 15.0)), expected,
                               rtol=1e-6)
    a, *_ = plain.step(expected)
    b, *_ = wrapped.step(residual)
    np.testing.assert_array_equal(a["joint_position"], b["joint_position"])


def test_a_zero_residual_is_the_pursuit_that_reaches_the_shelf_target(make_env):
    env = SubgoalResidual(make_env("ClutterReach-v1", subgoal_lookahead=0.2), gain=15.0)
    obs, _ = env.reset(seed=SHELF_SEED)
    assert np.abs(env.pursuit(obs)).max() == 1.0  # 0.2 rad ahead saturates some joint: full speed along the path
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(np.zeros(7, dtype=np.float32))
        done = terminated or truncated
    assert info["is_success"]


def test_the_wrapper_needs_an_env_its_base_controller_can_read(make_env):
    with pytest.raises(ValueError, match="needs a ClutterReach env made with observe_directions=True"):
        SubgoalResidual(make_env("ClutterReach-v1"), gain=15.0)
    with pytest.raises(ValueError, match="needs a ClutterReach env with control='joint_velocity'"):
        SubgoalResidual(make_env("ClutterReach-v1", control="ee_position", observe_directions=True), gain=2.0)
    with pytest.raises(ValueError, match="potential field needs 'lidar' in sensors"):
        SubgoalResidual(make_env("ClutterNav-v1", sensors=["imu"]), gain=1.5)
    with pytest.raises(ValueError, match="without a subgoal .* needs env_kwargs.observe_directions: true and "
                                         "control: joint_velocity"):
        config_for("ClutterReach-v1", {"env_kwargs": {"subgoal_lookahead": 0.0}})
    with pytest.raises(ValueError, match="pursuit, one of .*got 'ClutterReachGoal-v1'"):
        subgoal_pursuit("ClutterReachGoal-v1", 1.0)
    with pytest.raises(ValueError, match="needs the env"):
        subgoal_pursuit("ClutterNav-v1", 1.5)


def test_the_nav_pursuit_is_the_potential_field_on_the_goal_with_the_gain_as_turn_gain(make_env):
    env = SubgoalResidual(make_env("ClutterNav-v1", sensors=["lidar"]), gain=2.5)
    obs, _ = env.reset(seed=4)
    field = PotentialFieldNavigator.for_env(env)
    field.turn_gain = 2.5
    np.testing.assert_allclose(env.pursuit(obs), field(obs), atol=0)
    plain = make_env("ClutterNav-v1", sensors=["lidar"])
    plain.reset(seed=4)
    residual = np.array([0.2, -0.3], dtype=np.float32)
    a, *_ = plain.step(np.clip(field(obs) + residual, -1.0, 1.0))
    b, *_ = env.step(residual)
    np.testing.assert_array_equal(a["lidar"], b["lidar"])
    batch = {k: np.stack([v, v]) for k, v in obs.items()}
    np.testing.assert_allclose(env.pursuit(batch), [field(obs)] * 2, atol=0)


def test_a_loaded_residual_agent_adds_the_pursuit(tmp_path):
    tiny = {"timesteps": 64, "n_envs": 1, "train_layouts": 2, "validate_every": 0, "final_eval_episodes": 0,
            "checkpoint_every": 64, "ppo": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    run = start(config_for("ClutterReach-v1", tiny), tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    env = agent.make_env()
    obs, _ = env.reset(seed=SHELF_SEED)
    env.close()
    action, _ = agent.predict(obs)
    raw, _ = agent.model.predict(agent._normalizer.normalize_obs(obs), deterministic=True)
    pursuit = subgoal_pursuit("ClutterReach-v1", agent.config.residual_gain)
    np.testing.assert_allclose(action, residual_action(obs, raw, pursuit), rtol=1e-6)
    batch = {k: np.stack([v, v]) for k, v in obs.items()}
    actions, _ = agent.predict(batch)
    np.testing.assert_allclose(actions[0], action, atol=1e-6)


def test_the_report_says_the_reach_agent_is_a_residual_on_a_planner():
    from clutter_gym.training.report import _observation_line

    line = _observation_line(config_for("ClutterReach-v1"))
    assert "**Map-based agent.**" in line and "0.1 rad ahead on a joint-space path" in line
    assert "residuals on a pursuit" in line and "costmap" not in line


def test_the_fly_pursuit_is_the_cascaded_flyer_on_the_subgoal_for_one_observation_or_a_batch(make_env):
    env = SubgoalResidual(make_env("ClutterFly-v1", volume_size=(4.0, 4.0, 2.0), subgoal_lookahead=0.5), gain=1.5)
    obs, _ = env.reset(seed=3)
    flyer = CascadedFlyer.for_env(env, "subgoal")
    np.testing.assert_allclose(env.pursuit(obs), flyer(obs), atol=1e-7)
    for _ in range(10):
        obs, *_ = env.step(np.zeros(4, dtype=np.float32))
    batch = {k: np.stack([v, np.zeros_like(v)]) for k, v in obs.items()}
    batch["attitude"][1] = (0.0, 0.0, 1.0)  # level, at rest, on its target: the hover action
    actions = env.pursuit(batch)
    np.testing.assert_allclose(actions[0], flyer(obs), atol=1e-7)
    hover = env.unwrapped.robot.hover_action(env.unwrapped.sim.gravity)
    np.testing.assert_allclose(actions[1], hover, atol=1e-6)


def test_the_report_says_the_fly_agent_is_a_residual_on_a_position_controller():
    from clutter_gym.training.report import _observation_line

    line = _observation_line(config_for("ClutterFly-v1"))
    assert "**Map-based agent.**" in line and "0.5 m ahead on the shortest path" in line
    assert "residuals on a cascaded position controller" in line and "LIDAR" not in line


def test_the_potential_field_drives_the_same_on_a_forward_only_env(make_env):
    """reverse=False remaps the linear action; the field reads that from the env and drives the same path."""
    ends = []
    for reverse in (True, False):
        env = make_env("ClutterNav-v1", sensors=["lidar"], reverse=reverse)
        field = PotentialFieldNavigator.for_env(env)
        assert field.forward_only is not reverse
        obs, _ = env.reset(seed=5)
        for _ in range(60):
            obs, *_ = env.step(field(obs))
        ends.append(env.unwrapped.robot.state().position[:2])
    np.testing.assert_allclose(ends[0], ends[1], atol=1e-6)


def test_the_report_says_a_sensor_only_agent_reads_only_its_sensors():
    from clutter_gym.training.report import _observation_line

    line = _observation_line(config_for("ClutterNav-v1", {"env_kwargs": {"subgoal_lookahead": 0.0,
                                                                         "reverse": False}}))
    assert line.startswith("**Sensor-only agent.**") and "(lidar)" in line and "no map" in line
    assert "forwards only" in line and "Map-based" not in line


def test_a_loaded_sensor_only_agent_and_a_field_residual_agent_act_as_trained(tmp_path):
    """load() on the sensor-only block (forward only, bearing angle) and on a residual on the potential field."""
    from clutter_gym.training.config import read_hyperparams_file, user_settings

    tiny = {"timesteps": 64, "n_envs": 1, "validate_every": 0, "final_eval_episodes": 0, "checkpoint_every": 64,
            "ppo": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    sensors = user_settings(read_hyperparams_file("sensors-ppo"), "ClutterNav-v1")
    for name, extra in (("sensors", {}), ("field", {"residual_gain": 1.5})):
        run = start(config_for("ClutterNav-v1", {**sensors, **tiny, **extra}), tmp_path / name)
        train(run, progress=False)
        agent = load(run.root)
        env = agent.make_env()
        assert env.observation_space["goal"].shape == (4,) and env.unwrapped.forward_only
        obs, _ = env.reset(seed=2)
        action, _ = agent.predict(obs)
        raw, _ = agent.model.predict(agent._normalizer.normalize_obs(obs), deterministic=True)
        if extra:
            field = PotentialFieldNavigator.for_env(env)
            field.turn_gain = 1.5
            raw = residual_action(obs, raw, field)
        env.close()
        np.testing.assert_allclose(action, raw, rtol=1e-6)


def test_a_mapless_fly_residual_is_on_the_flyer_aimed_at_the_goal(make_env):
    """Without a subgoal the ClutterFly base is sensor-only: the position controller straight at the goal."""
    env = SubgoalResidual(make_env("ClutterFly-v1", volume_size=(4.0, 4.0, 2.0), sensors=["lidar"]), gain=1.5)
    obs, _ = env.reset(seed=3)
    flyer = CascadedFlyer.for_env(env, "goal")
    np.testing.assert_allclose(env.pursuit(obs), flyer(obs), atol=1e-7)
    plain = make_env("ClutterFly-v1", volume_size=(4.0, 4.0, 2.0), sensors=["lidar"])
    plain.reset(seed=3)
    residual = np.array([0.1, -0.2, 0.05, 0.0], dtype=np.float32)
    a, *_ = plain.step(np.clip(flyer(obs) + residual, -1.0, 1.0))
    b, *_ = env.step(residual)
    np.testing.assert_array_equal(a["lidar"], b["lidar"])
    with pytest.raises(ValueError, match="proximity field needs the env"):
        subgoal_pursuit("ClutterReach-v1", 2.0, mapless=True)


def test_a_loaded_mapless_fly_residual_agent_adds_the_flyer_on_the_goal(tmp_path):
    tiny = {"timesteps": 64, "n_envs": 1, "validate_every": 0, "final_eval_episodes": 0, "checkpoint_every": 64,
            "env_kwargs": {"subgoal_lookahead": 0.0, "sensors": ["lidar"], "volume_size": [4.0, 4.0, 2.0]},
            "ppo": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    run = start(config_for("ClutterFly-v1", tiny), tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    env = agent.make_env()
    obs, _ = env.reset(seed=1)
    assert "subgoal" not in obs
    flyer = CascadedFlyer.for_env(env, "goal", position_gain=agent.config.residual_gain)
    env.close()
    action, _ = agent.predict(obs)
    raw, _ = agent.model.predict(agent._normalizer.normalize_obs(obs), deterministic=True)
    np.testing.assert_allclose(action, residual_action(obs, raw, flyer), rtol=1e-6)
    from clutter_gym.training.report import _observation_line

    line = _observation_line(agent.config)
    assert line.startswith("**Sensor-only agent.**") and "(lidar)" in line
    assert "flying straight at the goal" in line and "potential field" not in line


def test_a_velocity_residual_steers_the_flyer_it_does_not_fly_it(make_env):
    """residual_space 'velocity': the policy's (3,) action offsets the flyer's commanded velocity (in units of its
    top speed, capped there) and the flyer's inner loops fly the sum; a zero offset is the flyer alone."""
    from clutter_gym.training.baselines import _capped
    from clutter_gym.training.residual import FACING_GAIN

    env = SubgoalResidual(make_env("ClutterFly-v1", volume_size=(4.0, 4.0, 2.0), sensors=["lidar"]), 1.5, "velocity")
    assert env.action_space.shape == (3,)
    obs, _ = env.reset(seed=3)
    flyer = CascadedFlyer.for_env(env, "goal", yaw_gain=FACING_GAIN)
    np.testing.assert_allclose(env.act(obs, np.zeros(3)), flyer(obs), atol=1e-7)
    sideways = np.array([0.0, 1.0, 0.0])
    wanted = _capped(flyer.velocity(obs) + flyer.max_speed * sideways, flyer.max_speed)
    assert np.linalg.norm(wanted) == pytest.approx(flyer.max_speed)
    np.testing.assert_allclose(env.act(obs, sideways), flyer.track(wanted, obs), atol=1e-7)
    batch = {k: np.stack([v, v]) for k, v in obs.items()}
    np.testing.assert_allclose(env.act(batch, np.stack([sideways, sideways]))[1], env.act(obs, sideways), atol=1e-7)
    with pytest.raises(ValueError, match="'velocity' is ClutterFly-v1's"):
        subgoal_pursuit("ClutterNav-v1", 1.5, make_env("ClutterNav-v1", sensors=["lidar"]), space="velocity")
    with pytest.raises(ValueError,
                       match=r"residual_space must be one of \('action', 'velocity', 'waypoint'\), got 'speed'"):
        subgoal_pursuit("ClutterFly-v1", 1.5, space="speed")
    with pytest.raises(ValueError, match="residual_space 'velocity' is ClutterFly-v1's"):
        config_for("ClutterNav-v1", {"residual_space": "velocity", "residual_gain": 1.5})
    with pytest.raises(ValueError, match="residual_space 'velocity' needs residual_gain > 0"):
        config_for("ClutterFly-v1", {"residual_space": "velocity", "residual_gain": 0.0})


def test_a_loaded_velocity_residual_agent_acts_on_plain_observations(tmp_path):
    tiny = {"timesteps": 64, "n_envs": 1, "validate_every": 0, "final_eval_episodes": 0, "checkpoint_every": 64,
            "residual_space": "velocity",
            "env_kwargs": {"subgoal_lookahead": 0.0, "sensors": ["lidar"], "volume_size": [4.0, 4.0, 2.0]},
            "ppo": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    run = start(config_for("ClutterFly-v1", tiny), tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    assert agent.model.action_space.shape == (3,)
    env = agent.make_env()  # the env's (4,) rate actions; the policy's (3,) velocity offsets
    obs, _ = env.reset(seed=1)
    action, _ = agent.predict(obs)
    assert action.shape == (4,)
    env.step(action)
    env.close()
    raw, _ = agent.model.predict(agent._normalizer.normalize_obs(obs), deterministic=True)
    wrapper = SubgoalResidual(agent.make_env(), agent.config.residual_gain, "velocity")
    np.testing.assert_allclose(action, wrapper.act(obs, raw), rtol=1e-6)
    wrapper.close()


def test_a_mapless_reach_residual_is_on_the_proximity_field_and_loads_as_trained(tmp_path, make_env):
    """Without a subgoal the ClutterReach base is sensor-only: the proximity field on the target, gain as its
    attraction; the wrapper and a loaded agent add the policy's action to it."""
    from clutter_gym.training.config import read_hyperparams_file, user_settings

    env = SubgoalResidual(make_env("ClutterReach-v1", observe_directions=True), gain=3.0)
    obs, _ = env.reset(seed=SHELF_SEED)
    field = ProximityFieldReacher.for_env(env, attraction=3.0)
    np.testing.assert_allclose(env.pursuit(obs), field(obs), atol=0)
    tiny = {"timesteps": 64, "n_envs": 1, "validate_every": 0, "final_eval_episodes": 0, "checkpoint_every": 64,
            "ppo": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    sensors = user_settings(read_hyperparams_file("sensors-ppo"), "ClutterReach-v1")
    run = start(config_for("ClutterReach-v1", {**sensors, **tiny}), tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    env = agent.make_env()
    obs, _ = env.reset(seed=SHELF_SEED)
    assert "subgoal" not in obs and "clearance_direction" in obs
    field = ProximityFieldReacher.for_env(env, attraction=agent.config.residual_gain)
    env.close()
    action, _ = agent.predict(obs)
    raw, _ = agent.model.predict(agent._normalizer.normalize_obs(obs), deterministic=True)
    np.testing.assert_allclose(action, residual_action(obs, raw, field), rtol=1e-6)
    from clutter_gym.training.report import _observation_line

    line = _observation_line(agent.config)
    assert line.startswith("**Sensor-only agent.**") and "proximity reading" in line and "lidar" not in line
    assert "joint-space potential field" in line


def test_residual_base_sets_the_flyers_gains_and_a_loaded_agent_keeps_them(tmp_path):
    tiny = {"timesteps": 64, "n_envs": 1, "validate_every": 0, "final_eval_episodes": 0, "checkpoint_every": 64,
            "residual_base": {"attitude_gain": 4.0, "max_speed": 0.8},
            "env_kwargs": {"subgoal_lookahead": 0.5, "observe_thrust_ratio": True, "volume_size": [4.0, 4.0, 2.0]},
            "ppo": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    run = start(config_for("ClutterFly-v1", tiny), tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    assert agent.config.residual_base == {"attitude_gain": 4.0, "max_speed": 0.8}
    env = agent.make_env(noise="harsh")
    obs, _ = env.reset(seed=1)
    for _ in range(20):  # away from rest, where the gains show
        obs, *_ = env.step(agent.predict(obs)[0])
    flyer = CascadedFlyer.for_env(env, "subgoal", position_gain=agent.config.residual_gain, attitude_gain=4.0,
                                  max_speed=0.8)
    env.close()
    action, _ = agent.predict(obs)
    raw, _ = agent.model.predict(agent._normalizer.normalize_obs(obs), deterministic=True)
    np.testing.assert_allclose(action, residual_action(obs, raw, flyer), rtol=1e-6)
    default = CascadedFlyer.for_env(agent.make_env(), "subgoal", position_gain=agent.config.residual_gain)
    assert not np.allclose(residual_action(obs, raw, default), action)


@pytest.mark.parametrize("settings, message", [
    ({"residual_gain": 1.5, "residual_base": {"attitude": 4.0}}, r"residual_base.attitude is not a gain of the flyer"),
    ({"residual_gain": 1.5, "residual_base": {"attitude_gain": 0.0}}, r"attitude_gain must be a number in \(0, 100"),
    ({"residual_gain": 1.5, "residual_base": {"attitude_gain": "4"}}, r"attitude_gain must be a number"),
    ({"residual_gain": 1.5, "residual_base": [4.0]}, r"residual_base must be a mapping"),
    ({"residual_gain": 0.0, "residual_base": {"attitude_gain": 4.0}}, r"residual_base needs residual_gain > 0"),
])
def test_residual_base_errors_name_the_field(settings, message):
    with pytest.raises(ValueError, match=message):
        config_for("ClutterFly-v1", settings)


def test_residual_base_is_the_flyers_only():
    with pytest.raises(ValueError, match="residual_base sets the gains of ClutterFly-v1's flyer"):
        config_for("ClutterNav-v1", {"residual_gain": 1.5, "residual_base": {"attitude_gain": 4.0}})
