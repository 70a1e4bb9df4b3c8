"""ClutterReach-v1 under dynamics='reduced' and 'auto': the motor law against its closed form, the choice and its
reasons, the model against full physics in empty space, the hand-over at a contact (no interpenetration), pybullet's
joints holding the model's state, the movable-obstacle rule and determinism."""

from __future__ import annotations

import numpy as np
import pytest

from clutter_gym.dynamics.arm_check import arm_gap
from clutter_gym.dynamics.arm_model import POSITION_GAIN, arm_ticks
from clutter_gym.dynamics.choice import AUTO_ARM_BOUND

EMPTY = {"n_obstacles": 0, "shelf": False}
#: a box on the table right under the Panda's hand at its ready pose
BOX_UNDER_HAND = {"scene": {"obstacles": [{"shape": "box", "size": [0.2, 0.2, 0.1], "position": [0.5, 0.0],
                                           "yaw": 0.0}], "target": [0.3, 0.3, 0.5]}}


def test_a_joint_steps_to_a_held_target_as_the_motor_law_says():
    """A target held with no velocity: the error shrinks by the gain every tick, (1 - kp)^n, the closed form of
    pybullet's position motor with an unlimited force. A velocity feed-forward ``w`` against a target held at 0 settles
    where the two balance, ``q = w dt / kp``, at rest."""
    q, v = np.zeros(2), np.zeros(2)
    arm_ticks(q, v, np.array([0.5, -0.2]), np.zeros(2), 1.0 / 240.0, 30)
    np.testing.assert_allclose(q, np.array([0.5, -0.2]) * (1.0 - (1.0 - POSITION_GAIN) ** 30), rtol=1e-12)
    q, v = np.zeros(1), np.zeros(1)
    turned = arm_ticks(q, v, np.zeros(1), np.array([1.0]), 1.0 / 240.0, 480)
    assert q[0] == pytest.approx(1.0 / 240.0 / POSITION_GAIN, abs=1e-12) and abs(v[0]) < 1e-12
    assert turned[0] == pytest.approx(q[0], rel=1e-12)  # it only ever turned one way


@pytest.mark.parametrize(("mode", "model"), [("auto", "reduced"), ("reduced", "reduced"), ("physics", "physics")])
def test_the_reset_says_which_model_runs_and_why(make_env, mode, model):
    env = make_env("ClutterReach-v1", dynamics=mode)
    _, info = env.reset(seed=0)
    assert info["dynamics"]["model"] == model
    assert f"dynamics={mode!r}" in info["dynamics"]["reason"]


@pytest.mark.parametrize(("robot", "model"), [("panda", "reduced"), ("kuka_iiwa", "reduced"), ("xarm6", "physics")])
def test_auto_takes_the_model_of_each_arm_whose_probe_it_drives_within_the_bound(make_env, robot, model):
    """Every arm gets a reduced model from its spec and URDF; the xArm6's weaker motors leave pybullet's hand over
    4 cm behind the ideal motors' on the probe, so ``"auto"`` keeps it on full physics."""
    env = make_env("ClutterReach-v1", robot=robot, dynamics="auto")
    arm = env.unwrapped.robot
    within = arm_gap(arm.model, arm.config, 240.0, 10, 20.0) <= AUTO_ARM_BOUND
    assert within is (model == "reduced")
    assert env.reset(seed=0)[1]["dynamics"]["model"] == model


def test_an_episode_with_a_movable_obstacle_runs_under_full_physics(make_env):
    env = make_env("ClutterReach-v1", dynamics="reduced", movable_obstacles=1.0)
    _, info = env.reset(seed=0)
    assert info["dynamics"]["model"] == "physics" and "movable" in info["dynamics"]["reason"]
    env.step(np.zeros(7, dtype=np.float32))
    assert env.unwrapped.dynamics.reduced_steps == 0


def test_in_empty_space_nearly_every_step_is_reduced_and_the_hand_follows_full_physics(make_env):
    """2 s of seeded joint commands with nothing around but the table: pybullet steps for no more than a step or two
    (the hand's swing can come within its reach of the table), its joints hold the model's state, and the hand ends
    within 2 cm of where full physics takes it (the model's ideal motors against pybullet's force-limited ones)."""
    commands = np.repeat(np.random.default_rng(0).uniform(-0.7, 0.7, (8, 7)), 5, axis=0).astype(np.float32)
    hands = {}
    for mode in ("physics", "reduced"):
        env = make_env("ClutterReach-v1", dynamics=mode, **EMPTY)
        env.reset(seed=0)
        for command in commands:
            env.step(command)
        base = env.unwrapped
        state = base.dynamics.state()
        hands[mode] = base.robot.ee_position(state)
        if mode == "reduced":
            assert base.dynamics.reduced_steps >= len(commands) - 2
            q, v = base.sim.actuation.joint_states(base.robot.body, base.robot.arm_joints)
            assert np.array_equal(q, state.joint_position) and np.array_equal(v, state.joint_velocity)
    assert np.linalg.norm(hands["physics"] - hands["reduced"]) < 0.02


def test_a_hand_driven_into_a_box_is_handed_to_full_physics_without_interpenetration(make_env):
    """Shoulder and elbow driven to bring the hand down onto a box: the steps that could reach it run under full
    physics, and the arm stops against it no deeper than full physics alone lets it."""
    down = np.array([0.0, 0.6, 0.0, 0.4, 0.0, 0.0, 0.0], dtype=np.float32)
    deepest = {}
    for mode in ("physics", "reduced"):
        env = make_env("ClutterReach-v1", dynamics=mode)
        env.reset(seed=0, options=BOX_UNDER_HAND)
        depth = np.inf
        for _ in range(60):
            _, _, _, _, info = env.step(down)
            depth = min(depth, info["min_clearance"])
        deepest[mode] = depth
    dynamics = env.unwrapped.dynamics
    assert dynamics.reduced_steps > 0 and dynamics.full_steps > 0
    assert deepest["physics"] < 1e-3  # it did reach the box
    assert deepest["reduced"] >= min(deepest["physics"], 0.0) - 1e-3


def test_the_same_seed_gives_the_same_trajectory(make_env):
    commands = np.random.default_rng(2).uniform(-1, 1, (60, 7)).astype(np.float32)
    runs = []
    for _ in range(2):
        env = make_env("ClutterReach-v1", dynamics="reduced")
        env.reset(seed=3)
        runs.append([env.step(c)[0]["joint_position"] for c in commands])
    assert np.array_equal(np.array(runs[0]), np.array(runs[1]))
