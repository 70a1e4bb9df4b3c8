"""ClutterNav-v1 under dynamics='reduced' and 'auto': the choice and its reasons, the fit, the model against full
physics on the open floor, the hand-over to full physics at a wall (no interpenetration, no energy gain), the
pose a camera sees, the dynamics randomisation, determinism and the refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.dynamics import fit_drive
from clutter_gym.dynamics.choice import AUTO_ERROR_BOUND
from clutter_gym.robots.registry import ground_robot

OPEN = {"arena_size": 8.0, "obstacle_density": 0.0, "sensors": ["lidar", "imu"]}
#: the base at the centre of the empty 8 m arena, facing +x, 4 m from every wall
CENTRE = {"scene": {"start": [0.0, 0.0, 0.0], "goal": [3.0, 3.0], "obstacles": []}}
#: a 0.4 m box 1 m ahead of the base
WALL_AHEAD = {"scene": {"start": [0.0, 0.0, 0.0], "goal": [-3.0, 3.0], "obstacles": [
    {"shape": "box", "position": [1.2, 0.0], "size": [0.4, 1.0, 0.4], "yaw": 0.0}]}}
FORWARD = np.array([1.0, 0.0], dtype=np.float32)


def _poses(env, commands, options):
    env.reset(seed=0, options=options)
    out = []
    for command in commands:
        env.step(np.asarray(command, dtype=np.float32))
        state = env.unwrapped.dynamics.state()
        out.append((state.position[0], state.position[1], state.yaw))
    return np.array(out)


def test_auto_takes_the_reduced_model_where_its_fit_is_within_the_bound():
    """The diffbot's fit reproduces its probe within the bound, the skid-steer Husky's does not (its yaw rate depends
    on how its wheels scrub, which a unicycle does not model)."""
    for name, within in (("diffbot", True), ("husky", False)):
        robot = ground_robot(name, "ClutterNav-v1", 0.5, 2.0)
        fit = fit_drive(robot.base, robot.config, 120.0, 10, 20.0)
        assert (fit.error <= AUTO_ERROR_BOUND) is within, (name, fit)


@pytest.mark.parametrize(("robot", "mode", "model"), [
    ("diffbot", "auto", "reduced"), ("husky", "auto", "physics"), ("diffbot", "reduced", "reduced"),
    ("diffbot", "physics", "physics"), ("omnibot", "auto", "physics")])
def test_the_reset_says_which_model_runs_and_why(make_env, robot, mode, model):
    env = make_env("ClutterNav-v1", robot=robot, dynamics=mode, obstacle_density=0.0)
    _, info = env.reset(seed=0)
    assert info["dynamics"]["model"] == model
    assert f"dynamics={mode!r}" in info["dynamics"]["reason"]


def test_an_episode_with_a_movable_obstacle_runs_under_full_physics(make_env):
    env = make_env("ClutterNav-v1", dynamics="reduced", movable_obstacles=1.0)
    _, info = env.reset(seed=0)
    assert info["dynamics"]["model"] == "physics" and "movable" in info["dynamics"]["reason"]
    env.step(FORWARD)
    assert env.unwrapped.dynamics.reduced_steps == 0


@pytest.mark.parametrize(("mode", "message"), [("fast", "dynamics must be one of"), (3, "dynamics must be one of")])
def test_an_unknown_mode_is_refused_by_name(make_env, mode, message):
    with pytest.raises(ValueError, match=message):
        make_env("ClutterNav-v1", dynamics=mode)


def test_a_base_without_a_reduced_model_is_refused_for_reduced(make_env):
    with pytest.raises(ValueError, match="dynamics='reduced' needs a differential drive"):
        make_env("ClutterNav-v1", robot="omnibot", dynamics="reduced")


def test_the_model_follows_full_physics_on_the_open_floor(make_env):
    """Seeded commands held 0.5 s each for 5 s: the reduced base ends within 0.1 m and 10 degrees of the full-physics
    one (benchmarks/dynamics/reduced_error.py measures 20 such drives: 90% within 0.061 m and 8.3 degrees at 5 s)."""
    commands = np.repeat(np.random.default_rng(1).uniform(-1, 1, (10, 2)), 10, axis=0)
    full = _poses(make_env("ClutterNav-v1", dynamics="physics", **OPEN), commands, CENTRE)
    reduced = _poses(make_env("ClutterNav-v1", dynamics="reduced", **OPEN), commands, CENTRE)
    assert math.dist(full[-1, :2], reduced[-1, :2]) < 0.1
    assert abs(math.remainder(full[-1, 2] - reduced[-1, 2], 2 * math.pi)) < math.radians(10)
    assert np.linalg.norm(np.diff(full[:, :2], axis=0), axis=1).sum() > 1.0  # it went somewhere


def test_a_drive_into_a_box_is_handed_to_full_physics_without_interpenetration_or_energy_gain(make_env):
    """Full speed at a box 1 m ahead: the steps far from it run reduced, the first step within reach of it runs
    under full physics from the model's speed (pybullet's body takes the model's velocity, no more), the base never
    exceeds its commanded speed, and it stops against the box no deeper than full physics alone lets it."""
    depths = {}
    for mode in ("physics", "reduced"):
        env = make_env("ClutterNav-v1", dynamics=mode, **OPEN)
        env.reset(seed=0, options=WALL_AHEAD)
        base = env.unwrapped
        deepest, fastest = math.inf, 0.0
        for _ in range(60):
            was_full = getattr(base.dynamics, "full", True)
            speed_before = float(base.dynamics.state().linear_velocity[0])
            obs, _, _, _, info = env.step(FORWARD)
            if mode == "reduced" and not was_full and base.dynamics.full:  # handed over for the next step
                _, _, linear, _ = base.sim.base_state(base.robot.body)
                assert linear[0] == pytest.approx(float(obs["velocity"][0]), abs=1e-3)
                assert linear[0] <= speed_before + 0.05 * 4.0 + 1e-6  # no faster than one step's acceleration
            deepest = min(deepest, info["min_clearance"])
            fastest = max(fastest, float(obs["velocity"][0]))
        depths[mode] = deepest
        assert fastest <= 0.5 * 1.01
        if mode == "reduced":
            assert base.dynamics.reduced_steps > 20 and base.dynamics.full_steps > 10
    assert depths["reduced"] >= min(depths["physics"], 0.0) - 1e-3


def test_the_same_seed_gives_the_same_trajectory(make_env):
    commands = np.random.default_rng(2).uniform(-1, 1, (80, 2))
    a, b = (_poses(make_env("ClutterNav-v1", dynamics="reduced"), commands, None) for _ in range(2))
    assert np.array_equal(a, b)


def test_a_camera_sees_the_base_where_the_model_has_it(make_env):
    """With something that draws (a render mode), each reduced step puts the pybullet body at the model's pose."""
    env = make_env("ClutterNav-v1", dynamics="reduced", render_mode="rgb_array", **OPEN)
    env.reset(seed=0, options=CENTRE)
    for _ in range(10):
        env.step(np.array([1.0, 0.5], dtype=np.float32))
    base = env.unwrapped
    state = base.dynamics.state()
    com, rotation, _, _ = base.sim.base_state(base.robot.body)
    assert np.asarray(com) == pytest.approx(state.position + state.rotation @ base.robot.com_offset, abs=1e-9)
    assert np.reshape(rotation, (3, 3)) == pytest.approx(state.rotation, abs=1e-6)
    assert env.render().shape[2] == 3


@pytest.mark.parametrize("sample", [DynamicsSample(motor_scale=0.5), DynamicsSample(mass_scale=2.0),
                                    DynamicsSample(friction_scale=0.5)], ids=["motors", "mass", "grip"])
def test_weaker_motors_more_mass_or_less_grip_accelerate_the_model_slower(make_env, sample):
    """Half the motors' strength, twice the mass or half the floor's grip halves the model's acceleration limit: 0.1 s
    into a full forward command from rest the base has about half the speed of the nominal one."""
    speeds = []
    for episode in (DynamicsSample(), sample):
        env = make_env("ClutterNav-v1", dynamics="reduced", **OPEN)
        env.reset(seed=0, options=CENTRE)
        env.unwrapped.dynamics.apply_dynamics(episode)
        for _ in range(2):
            obs, *_ = env.step(FORWARD)
        speeds.append(float(obs["velocity"][0]))
    assert speeds[1] == pytest.approx(0.5 * speeds[0], rel=0.15)


def test_the_wheels_roll_with_the_model_so_odometry_reads_its_drive(make_env):
    """The reduced model turns the pybullet body's wheels by the distance each side rolled, so the wheel odometry
    (which reads the wheels' angles) dead-reckons the model's drive: after 2 s of an arc, within 2% of the distance
    and 0.03 rad of the heading (the difference being the model's scrub, which the wheels do not see)."""
    env = make_env("ClutterNav-v1", dynamics="reduced", sensors=["lidar", "odometry"], arena_size=8.0,
                   obstacle_density=0.0)
    env.reset(seed=0, options=CENTRE)
    for _ in range(40):
        obs, *_ = env.step(np.array([0.8, 0.3], dtype=np.float32))
    state = env.unwrapped.dynamics.state()
    x, y, sin_yaw, cos_yaw = obs["odometry"][:4]
    assert math.hypot(x, y) == pytest.approx(math.hypot(*state.position[:2]), rel=0.02)
    assert abs(math.remainder(math.atan2(sin_yaw, cos_yaw) - state.yaw, 2 * math.pi)) < 0.03
