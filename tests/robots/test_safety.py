"""The collision monitor: its arc prediction and speed choice against hand-worked cases, and in the env."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import empty_scene

from clutter_gym.robots.safety import SafetyConfig, SafetyFilter, arc

RADIUS, V_MAX, W_MAX = 0.17, 0.5, 2.0
ANGLES = -math.pi + 2 * math.pi * np.arange(360) / 360  # 1-degree beams, beam 180 points along +x


DT = 0.05  # 20 Hz commands


def monitor(horizon=0.3, margin=0.02, recovery=0.0) -> SafetyFilter:
    return SafetyFilter(SafetyConfig(horizon, margin, recovery), RADIUS, V_MAX, W_MAX, ANGLES, (0.0, 0.0),
                        max_range=3.5, control_dt=DT)


def scan(hits: dict[int, float]) -> np.ndarray:
    """A scan with no returns except the given beams, {azimuth in degrees: range in m}."""
    ranges = np.full(len(ANGLES), 3.5)
    for degrees, r in hits.items():
        ranges[degrees + 180] = r
    return ranges


def test_arc_is_the_unicycle_solution():
    t = np.array([0.5, math.pi / 2])
    np.testing.assert_allclose(arc(0.4, 0.0, t), [[0.2, 0.0], [0.4 * math.pi / 2, 0.0]])
    # v = w = 1: a unit circle about (0, 1); a quarter turn ends at (1, 1)
    np.testing.assert_allclose(arc(1.0, 1.0, t)[1], [1.0, 1.0], atol=1e-12)
    # backwards with the same yaw rate: the circle about (0, -1)
    np.testing.assert_allclose(arc(-1.0, 1.0, t)[1], [-1.0, -1.0], atol=1e-12)


@pytest.mark.parametrize(
    "ahead, expected",
    [
        # full speed covers 0.5 m/s * 0.3 s = 0.15 m; the footprint must keep 0.17 + 0.02 = 0.19 m from the point
        (0.345, 1.0),  # 0.345 - 0.15 = 0.195 >= 0.19
        (0.335, 0.75),  # 1.0 leaves 0.185; 0.75 covers 0.1125 and leaves 0.2225
        (0.28, 0.5),  # 0.75 leaves 0.1675; 0.5 covers 0.075 and leaves 0.205
        (0.25, 0.25),  # 0.5 leaves 0.175; 0.25 covers 0.0375 and leaves 0.2125
        (0.21, 0.0),  # 0.25 leaves 0.1725
    ],
)
def test_speed_falls_to_the_largest_step_that_keeps_the_margin_straight_ahead(ahead, expected):
    assert monitor().scale(np.array([1.0, 0.0]), scan({0: ahead})) == expected


def test_only_the_direction_of_travel_matters():
    m = monitor()
    behind = scan({-180: 0.2})
    assert m.scale(np.array([1.0, 0.0]), behind) == 1.0
    assert m.scale(np.array([-1.0, 0.0]), behind) == 0.0
    # a turning command sweeps its arc: an obstacle off to the left is hit only when turning left
    left = scan({30: 0.33})
    assert m.scale(np.array([1.0, 0.0]), left) == 1.0
    assert m.scale(np.array([1.0, 1.0]), left) < 1.0


def test_a_robot_already_inside_the_margin_may_move_away_but_not_closer():
    m = monitor()
    beside = scan({90: 0.18})  # 0.01 m of clearance on the left, less than the 0.02 margin
    assert m.scale(np.array([1.0, 0.0]), beside) == 1.0  # driving straight keeps (and then grows) the distance
    # a tight left turn (0.125 m/s, 2 rad/s: a 0.0625 m radius) swings the footprint towards it; one to the right
    # swings it away. (A wide left arc, radius over 0.18 m, circles around the point and is allowed.)
    assert m.scale(np.array([0.25, 1.0]), beside) == 0.0
    assert m.scale(np.array([0.25, -1.0]), beside) == 1.0
    assert m.scale(np.array([1.0, 1.0]), beside) == 1.0


def test_no_return_and_turning_in_place_pass_unchanged():
    m = monitor()
    ranges = scan({0: 0.2})
    ranges[:10] = np.inf  # a profile may report "no return" as inf
    command = np.array([0.0, 1.0])
    out, s = m.filter(command, ranges)
    assert s == 1.0 and out is command
    assert m.scale(np.array([1.0, 0.0]), np.full(len(ANGLES), np.inf)) == 1.0
    out, s = m.filter(np.array([0.8, -0.3]), ranges)
    np.testing.assert_array_equal(out, [0.0, -0.3])


def drive(m: SafetyFilter, command, ranges, steps: int) -> list[tuple[np.ndarray, float, bool]]:
    """``steps`` calls of ``m.filter`` with the same command and scan: (driven command, scale, recovering)."""
    out = []
    for _ in range(steps):
        driven, s = m.filter(np.array(command, dtype=float), ranges)
        out.append((driven, s, m.recovering))
    return out


@pytest.mark.parametrize("side, spin", [(10, -1.0), (-10, 1.0)])
def test_a_pinned_robot_spins_away_from_the_nearest_return_then_gets_control_back(side, spin):
    # 0.5 s of holding at 20 Hz = 10 steps; the spin turns RECOVERY_TURN = 0.8 rad at 2 rad/s: ceil(8.0) = 8 steps
    m = monitor(recovery=0.5)
    blocked = scan({side: 0.2, side + 40: 0.6})  # nearest return 10 degrees to one side, 0.2 m away
    steps = drive(m, [1.0, 0.3], blocked, 10 + 8 + 1)
    for driven, s, recovering in steps[:10]:  # held: no forward speed, the policy's yaw rate
        assert s == 0.0 and not recovering
        np.testing.assert_array_equal(driven, [0.0, 0.3])
    for driven, s, recovering in steps[10:18]:  # the spin ignores the command and turns away from the return
        assert s == 0.0 and recovering
        np.testing.assert_array_equal(driven, [0.0, spin])
    driven, s, recovering = steps[18]
    assert not recovering and s == 0.0 and driven[1] == 0.3  # the policy again, held again from a count of 0


def test_only_a_whole_held_command_counts_towards_the_recovery():
    m = monitor(recovery=0.5)
    assert all(not r for _, s, r in drive(m, [1.0, 0.0], scan({0: 0.25}), 50) if s == 0.25)  # slowed, never spun
    pinned = scan({0: 0.2})
    drive(m, [1.0, 0.0], pinned, 9)
    drive(m, [0.0, 1.0], pinned, 1)  # a command without forward speed is not held: the count restarts
    assert not any(r for _, _, r in drive(m, [1.0, 0.0], pinned, 10))
    assert drive(m, [1.0, 0.0], pinned, 1)[0][2]
    m.reset()  # a new episode drops the spin under way
    assert not drive(m, [1.0, 0.0], pinned, 1)[0][2]
    never = monitor(recovery=0.0)
    assert not any(r for _, _, r in drive(never, [1.0, 0.0], pinned, 200))


@pytest.mark.parametrize("field, value", [("horizon", -0.1), ("horizon", 2.5), ("margin", -0.01), ("margin", np.nan),
                                          ("recovery", -0.5), ("recovery", 11.0), ("recovery", np.inf)])
def test_config_names_the_field_and_range(field, value):
    with pytest.raises(ValueError, match=f"safety_{field} must be in"):
        SafetyConfig(**{field: value})


def test_env_stops_short_of_a_wall_that_it_would_otherwise_hit(make_env):
    wall = {"shape": "box", "size": [0.2, 2.0, 0.5], "position": [0.8, 0.0], "yaw": 0.0}
    outcomes = {}
    for horizon in (0.0, 0.3):
        env = make_env(sensors=["lidar"], safety_horizon=horizon)
        env.reset(options={"scene": empty_scene(obstacles=[wall], goal=(-2.0, 2.0))})
        infos = [env.step(np.array([1.0, 0.0]))[4] for _ in range(40)]
        outcomes[horizon] = (max(i["cost"] for i in infos), min(i["min_clearance"] for i in infos), infos[-1])
    assert outcomes[0.0][0] == 1.0  # without the monitor the robot drives into the wall
    cost, clearance, last = outcomes[0.3]
    assert cost == 0.0 and clearance > 0.0 and last["safety_scale"] == 0.0
    # it stops once even a quarter of full speed would break the margin: within 0.02 + 0.25 * 0.15 m of the wall
    assert 0.0 < clearance < 0.02 + 0.25 * V_MAX * 0.3 + 0.01


def test_env_recovery_turns_a_pinned_robot_away_without_contact(make_env):
    wall = {"shape": "box", "size": [0.2, 2.0, 0.5], "position": [0.8, 0.3], "yaw": 0.4}  # leaning, nearest on the left
    env = make_env(sensors=["lidar"], safety_horizon=0.3, safety_recovery=0.5)
    env.reset(options={"scene": empty_scene(obstacles=[wall], goal=(-2.0, 2.0))})
    infos = [env.step(np.array([1.0, 0.0]))[4] for _ in range(60)]
    spinning = [i["safety_recovery"] for i in infos]
    assert max(i["cost"] for i in infos) == 0.0
    assert 8 <= sum(spinning) <= 24  # at least one spin of 8 steps; held for 10 steps before each
    first = spinning.index(True)
    assert first >= 10 and all(spinning[first:first + 8])
    yaw = env.unwrapped.robot.state().yaw
    assert yaw < -0.3  # turned right, away from the wall's near end on the left


def test_env_rejects_a_monitor_without_a_2d_lidar(make_env):
    with pytest.raises(ValueError, match=r"safety_horizon must be in \[0, 2\] seconds"):
        make_env(safety_horizon=-0.1)
    with pytest.raises(ValueError, match=r"safety_margin must be in \[0, 0.5\] metres"):
        make_env(safety_margin=-1.0)  # checked even with the monitor off
    with pytest.raises(ValueError, match=r"safety_recovery must be in \[0, 10\] seconds"):
        make_env(safety_recovery=-1.0)
    with pytest.raises(ValueError, match="safety_recovery > 0 needs the collision monitor on"):
        make_env(safety_recovery=0.5)  # a recovery without a monitor would never run
    with pytest.raises(ValueError, match="safety_horizon > 0 needs a 2D LIDAR"):
        make_env(sensors=["imu"], safety_horizon=0.3)
    with pytest.raises(ValueError, match="safety_horizon > 0 needs a 2D LIDAR"):
        make_env(lidar_channels=4, lidar_vertical_fov=0.3, safety_horizon=0.3)
