"""ClutterReach-v1's hand controller and the line-up teachers: the hand moves by the commanded displacement and
turns to the commanded pitch in the env, a joint at its limit is held, and the hand-space teacher reaches a target
in the open by its route."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from clutter_gym.planning.hand_pose import LIMIT_BAND, HandPose, hand_axis
from clutter_gym.training.hand_controller import HAND_STEP, PITCH_MID, PITCH_SCALE, HandController
from clutter_gym.training.residual import SubgoalResidual, policy_action_space
from clutter_gym.training.teachers import make_teacher

OPEN = {"obstacles": [], "start": [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785], "target": [0.45, 0.2, 0.3]}


@pytest.fixture
def hand_env(make_env):
    return SubgoalResidual(make_env("ClutterReach-v1", observe_directions=True), 0.0, space="waypoint")


def test_the_hand_moves_by_the_commanded_displacement_and_keeps_pointing_down(hand_env):
    obs, _ = hand_env.reset(seed=0, options={"scene": OPEN})
    start = obs["ee_position"].copy()
    for _ in range(10):  # 1 cm a step along +x, pitch +1: pointing down, as the start pose does
        obs, *_ = hand_env.step(np.array([0.5, 0.0, 0.0, 1.0], dtype=np.float32))
    moved = obs["ee_position"] - start
    # the joints' position motors lag their targets by about one step, so ten steps cover 8-10 cm
    assert 0.08 <= moved[0] <= 0.105 and np.abs(moved[1:]).max() < 0.01
    hand = HandPose(hand_env.unwrapped.robot.model).frames(obs["joint_position"].astype(float))[0]
    assert hand[2, 2] < -0.99


def test_the_hand_turns_to_the_commanded_pitch_where_it_stands(hand_env):
    obs, _ = hand_env.reset(seed=0, options={"scene": OPEN})
    start = obs["ee_position"].copy()
    for _ in range(40):  # halfway between level and down (action 0), no displacement
        obs, *_ = hand_env.step(np.zeros(4, dtype=np.float32))
    hand = HandPose(hand_env.unwrapped.robot.model).frames(obs["joint_position"].astype(float))[0]
    wanted = hand_axis(np.array(OPEN["target"]), PITCH_MID)
    assert np.linalg.norm(hand[:3, 2] - wanted) < 0.05
    assert abs(hand[2, 1]) < 0.05  # fingers' opening level
    # each step holds the hand where it is then, so the linearised turn creeps: a few cm over 45 degrees
    assert np.linalg.norm(obs["ee_position"] - start) < 0.05


def test_a_joint_at_its_limit_is_held(hand_env):
    hand = HandPose(hand_env.unwrapped.robot.model)
    q = np.array(OPEN["start"])
    q[3] = hand.lower[3] + 0.5 * LIMIT_BAND  # the elbow folded to its limit
    here = hand.frames(q)[0]
    further = hand.step(q, here[:3, 3] + np.array([-0.05, 0.0, 0.05]), here[:3, 2])[0]  # pulled in and up
    free = hand.step(q, here[:3, 3] + np.array([0.05, 0.0, 0.0]), here[:3, 2])[0]
    assert q[3] + further[3] >= hand.lower[3] + 0.5 * LIMIT_BAND - 1e-12
    assert np.abs(free).max() > 0.0


def test_the_policy_acts_in_four_numbers_and_the_controller_keeps_actions_in_range(hand_env):
    assert policy_action_space(hand_env.unwrapped.action_space, "waypoint", "ClutterReach-v1").shape == (4,)
    controller = HandController.for_env(hand_env)
    obs, _ = hand_env.reset(seed=3)
    for move in ([1, 1, 1, -1], [-1, 0, 1, 1], [0, 0, 0, 0]):
        action = controller.toward(obs, *(np.array(move) * controller.waypoint_scales))
        assert action.shape == (7,) and np.all(np.abs(action) <= 1.0) and np.all(np.isfinite(action))


def test_the_hand_teacher_reaches_a_target_in_the_open_over_it_and_down(hand_env):
    teacher = make_teacher("ClutterReach-v1", "line-up", hand_env, space="waypoint")
    obs, info = hand_env.reset(seed=0, options={"scene": OPEN})
    teacher.reset()
    teacher(obs, info)  # plans the layout's route
    points, pitch = teacher.route
    assert pitch == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(points[-1], OPEN["target"])
    for _ in range(100):
        label = teacher(obs, info)
        assert label.shape == (4,) and np.all(np.abs(label) <= 1.0)
        assert label[3] == pytest.approx((math.pi / 2 - PITCH_MID) / PITCH_SCALE)
        obs, _, terminated, truncated, info = hand_env.step(label)
        if terminated or truncated:
            break
    assert info["is_success"] and info["cost"] == 0.0
    assert HAND_STEP == pytest.approx(hand_env.pursuit.waypoint_scales[0])


def test_the_planner_teacher_refuses_the_hand_space(hand_env):
    with pytest.raises(ValueError, match="needs teacher.name 'line-up'"):
        make_teacher("ClutterReach-v1", "planner", hand_env, space="waypoint")


def test_the_reach_benchmarks_drive_the_teachers_in_either_space_and_the_controller_alone():
    """The commands behind docs/learning.md's ClutterReach teacher rows and its controller-alone row."""
    from helpers import run_benchmark

    for args, teacher in ((("--teachers", "line-up"), "line-up"), (("--space", "action", "--teachers", "planner"),
                                                                    "planner")):
        done = run_benchmark("benchmarks.learning.teacher_realisability", "--env", "ClutterReach-v1", "--episodes",
                             "1", *args)
        assert done.returncode == 0, done.stderr[-2000:]
        assert re.search(rf"^\| {teacher} \| \d+% \[\d+%, \d+%\] / \d+% \|$", done.stdout, re.M), done.stdout
    done = run_benchmark("benchmarks.learning.reach_diagnosis", "--over-and-down", "--episodes", "2")
    assert done.returncode == 0, done.stderr[-2000:]
    rows = re.findall(r"^\| (table|shelf) \| (\d+) \| \d+ \| \d+ \| \d+ \|$", done.stdout, re.M)
    assert [place for place, _ in rows] == ["table", "shelf"] and sum(int(n) for _, n in rows) == 2
