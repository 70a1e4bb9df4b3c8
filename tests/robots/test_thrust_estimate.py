"""The thrust-ratio estimate against closed forms: the filter's response to exact samples, what it skips and clips,
the quadrotor's estimate of an airframe whose mass and motors differ from its model, and the env's entry."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.robots import Quadrotor, QuadrotorConfig
from clutter_gym.robots.thrust_estimate import RATIO_BOUNDS, ThrustRatioEstimator
from clutter_gym.sim import Sim

MASS, G, DT, TAU = 0.027, 9.81, 1.0 / 240.0, 0.25


def _tilted_z(angle: float) -> tuple[float, float, float]:
    return (math.sin(angle), 0.0, math.cos(angle))


def feed(estimator: ThrustRatioEstimator, ratio: float, thrust: float, ticks: int, body_z=(0.0, 0.0, 1.0)) -> None:
    """``ticks`` ticks of an airframe whose rotors give ``ratio`` x the model's specific force along ``body_z``."""
    v = np.zeros(3)
    estimator.update(body_z, tuple(v), thrust)
    for _ in range(ticks):
        v = v + DT * (ratio * thrust / MASS * np.asarray(body_z) - np.array([0.0, 0.0, G]))
        estimator.update(body_z, tuple(v), thrust)


@pytest.mark.parametrize("ratio, angle", [(0.75, 0.0), (1.2, 0.4), (1.0, -0.3)])
def test_filter_approaches_the_true_ratio_as_a_first_order_lag(ratio, angle):
    estimator = ThrustRatioEstimator(MASS, G, DT, TAU)
    ticks = 60
    feed(estimator, ratio, 0.3, ticks, _tilted_z(angle))
    # exact samples: the error left after n samples is (1 - gain)^n of the first one
    expected = ratio + (1.0 - ratio) * math.exp(-ticks * DT / TAU)
    assert estimator.ratio == pytest.approx(expected, abs=1e-9)


def test_reset_returns_to_the_nominal_model_and_forgets_the_last_velocity():
    estimator = ThrustRatioEstimator(MASS, G, DT, TAU)
    feed(estimator, 0.8, 0.3, 100)
    assert estimator.ratio < 0.9
    estimator.reset()
    assert estimator.ratio == 1.0
    estimator.update((0.0, 0.0, 1.0), (5.0, 5.0, 5.0), 0.3)  # no velocity to difference against: no sample
    assert estimator.ratio == 1.0


def test_samples_without_thrust_are_skipped_and_wild_ones_clipped():
    estimator = ThrustRatioEstimator(MASS, G, DT, TAU)
    feed(estimator, 1.0, 0.05 * MASS * G, 100)  # under a tenth of the weight: a ratio of two small numbers
    assert estimator.ratio == 1.0
    estimator.reset()
    estimator.update((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), 0.3)
    estimator.update((0.0, 0.0, 1.0), (0.0, 0.0, 100.0), 0.3)  # a contact's kick: 24,000 m/s^2
    assert estimator.ratio == pytest.approx(1.0 + estimator.gain * (RATIO_BOUNDS[1] - 1.0))


def test_time_constant_must_be_positive():
    with pytest.raises(ValueError, match="time_constant"):
        ThrustRatioEstimator(MASS, G, DT, 0.0)
    with pytest.raises(ValueError, match="thrust_ratio_time_constant"):
        QuadrotorConfig(thrust_ratio_time_constant=-1.0)
    with pytest.raises(ValueError, match="observe_thrust_ratio"):
        QuadrotorConfig(observe_thrust_ratio="yes")


def airframe(sim: Sim, mass_scale: float, motor_scale: float) -> Quadrotor:
    """A quadrotor estimating its thrust ratio, 5 m up in ``sim``, hovering, with these dynamics."""
    robot = Quadrotor(QuadrotorConfig(observe_thrust_ratio=True))
    robot.load(sim)
    robot.reset_to((0.0, 0.0, 5.0, 0.0))
    robot.apply_dynamics(DynamicsSample(mass_scale=mass_scale, motor_scale=motor_scale))
    return robot


@pytest.mark.parametrize("mass_scale, motor_scale", [(1.2, 0.9), (0.85, 1.15)])
def test_quadrotor_estimates_its_motor_strength_over_its_mass_scale_in_flight(mass_scale, motor_scale):
    sim = Sim(physics_hz=240.0)
    try:
        robot = airframe(sim, mass_scale, motor_scale)
        assert robot.observe(robot.state())["thrust_ratio"][0] == 1.0
        robot.apply_action(np.array([robot.hover_action(G)[0], 0.3, -0.2, 0.1]))  # tilting and yawing as it goes
        for _ in range(480):  # 2 s: eight time constants
            robot.before_tick()
            sim.step()
        estimate = robot.observe(robot.state())["thrust_ratio"]
        assert estimate.dtype == np.float32 and estimate.shape == (1,)
        # pybullet's velocity is exact at the ticks, so each sample is exact; float32 and exp(-8) of the start left
        assert estimate[0] == pytest.approx(motor_scale / mass_scale, abs=1e-3 + math.exp(-8))
    finally:
        sim.close()


def test_env_entry_is_off_by_default_and_new_each_episode():
    plain = gym.make("ClutterFly-v1")
    try:
        assert "thrust_ratio" not in plain.observation_space.spaces
    finally:
        plain.close()
    env = gym.make("ClutterFly-v1", sensors=[], noise="harsh", observe_thrust_ratio=True)
    try:
        assert env.observation_space["thrust_ratio"].shape == (1,)
        obs, _ = env.reset(seed=3)
        assert obs["thrust_ratio"][0] == 1.0 and obs in env.observation_space
        for _ in range(30):
            obs, *_ = env.step(np.zeros(4, dtype=np.float32))
        robot = env.unwrapped.robot
        truth = robot._dynamics.motor_scale / robot._dynamics.mass_scale
        assert abs(obs["thrust_ratio"][0] - truth) < abs(1.0 - truth)  # moving towards this episode's airframe
        obs, _ = env.reset(seed=4)
        assert obs["thrust_ratio"][0] == 1.0  # nothing of the last episode's airframe carries over
    finally:
        env.close()
    with pytest.raises(ValueError, match="observe_thrust_ratio"):
        gym.make("ClutterFly-v1", observe_thrust_ratio=1)


def hover_error(mass_scale: float, motor_scale: float, reads_ratio: bool, seconds: float = 10.0) -> float:
    """Metres the flyer, holding a point 5 m up in a bare world, ends below it on an airframe with these scales."""
    from clutter_gym.training.baselines import CascadedFlyer

    sim = Sim(physics_hz=240.0)
    try:
        robot = airframe(sim, mass_scale, motor_scale)
        flyer = CascadedFlyer.nominal("goal")
        target = np.array([0.0, 0.0, 5.0])
        for _ in range(int(seconds * 30)):  # 30 Hz control, 8 ticks a step
            state = robot.state()
            obs = robot.observe(state)
            obs["goal"] = state.rotation.T @ (target - state.position)
            if not reads_ratio:
                del obs["thrust_ratio"]
            robot.apply_action(flyer(obs))
            for _ in range(8):
                robot.before_tick()
                sim.step()
        return float(target[2] - robot.state().position[2])
    finally:
        sim.close()


@pytest.mark.parametrize("mass_scale, motor_scale", [(1.1, 0.88), (0.9, 1.15)])
def test_the_flyer_holds_its_altitude_on_an_off_nominal_airframe_only_with_the_estimate(mass_scale, motor_scale):
    """The flyer's loops are proportional: on the datasheet's hover thrust an airframe getting ``r`` times the
    model's specific force settles where the commanded acceleration makes up for it, ``a = g / r - g``, i.e.
    ``a / (velocity_gain * position_gain)`` below its target (0.55 m for r = 0.8; ``a`` within the flyer's
    ``max_accel``). Reading ``thrust_ratio`` it holds the target."""
    from clutter_gym.training.baselines import CascadedFlyer

    flyer = CascadedFlyer.nominal("goal")
    r = motor_scale / mass_scale
    sag = (G / r - G) / (flyer.velocity_gain * flyer.position_gain)
    assert hover_error(mass_scale, motor_scale, reads_ratio=False) == pytest.approx(sag, rel=0.02)
    assert abs(hover_error(mass_scale, motor_scale, reads_ratio=True)) < 2e-3
