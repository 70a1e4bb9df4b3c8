"""Settings at the edge of their allowed ranges work at reset, not only at gym.make."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from helpers import empty_scene


def test_the_largest_arena_at_the_highest_density_resets_and_steps():
    env = gym.make("ClutterNav-v1", arena_size=30.0, obstacle_density=0.3)
    for seed in (0, 1):
        obs, info = env.reset(seed=seed)
        assert len(env.unwrapped.scene.obstacles) > 1000
        assert info["min_clearance"] > 0.0
        for _ in range(10):
            obs, reward, *_ = env.step(env.action_space.sample())
            assert all(np.all(np.isfinite(v)) for v in obs.values()) and np.isfinite(reward)
    env.close()


@pytest.mark.parametrize(("size", "density"), [((2.0, 2.0, 1.0), 0.25), ((2.0, 30.0, 1.0), 0.25),
                                               ((10.0, 10.0, 1.0), 0.05), ((30.0, 30.0, 5.0), 0.05)])
def test_clutter_fly_volumes_at_the_edges_of_their_sizes_reset_and_hover(size, density):
    """volume_size z down to 1 m, as docs/envs.md gives it (the env refused heights under 2 m, where its wall openings
    did not fit under the top); x and y from 2 to 30 m. Two seeded layouts each, ten hover steps without an end."""
    env = gym.make("ClutterFly-v1", volume_size=size, obstacle_density=density, sensors=("imu", "lidar"))
    hover = env.unwrapped.robot.hover_action(9.81).astype(np.float32)
    for seed in (0, 1):
        obs, info = env.reset(seed=seed)
        scene = env.unwrapped.scene
        assert 0.0 < scene.start[2] < size[2] and 0.0 < scene.goal[2] < size[2]
        assert info["min_clearance"] > 0.0
        for _ in range(10):
            obs, reward, terminated, truncated, info = env.step(hover)
            assert all(np.all(np.isfinite(v)) for v in obs.values()) and np.isfinite(reward)
            assert not terminated
    env.close()


# ----------------------------------------------------------------------------- the physics rate at each env's floor
# Below the floor each env declares, its stiffest dynamics break (docs/envs.md, "Physics rate" has the sweep); at
# the floor they must still hold, so a floor lowered past where they break fails here.


def tilt_degrees(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(min(1.0, float(rotation[2, 2]))))


def test_at_its_lowest_physics_rate_clutter_nav_stops_and_stays_stopped():
    """Full speed for 2 s, then zero: after a second to stop, the robot creeps less than a millimetre in the next
    two and never tilts (at 15 Hz it crept 32 mm, at 2 Hz it turned over)."""
    from clutter_gym.clutter_nav import MIN_PHYSICS_HZ

    env = gym.make("ClutterNav-v1", physics_hz=MIN_PHYSICS_HZ, control_hz=20.0, sensors=())
    env.reset(seed=0, options={"scene": empty_scene(start=(-2.0, 0.0, 0.0))})
    robot, tilt = env.unwrapped.robot, 0.0
    for action, seconds in (((1.0, 0.0), 2.0), ((0.0, 0.0), 1.0)):
        for _ in range(int(20 * seconds)):
            env.step(np.array(action, dtype=np.float32))
            tilt = max(tilt, tilt_degrees(robot.state().rotation))
    stopped = robot.state().position.copy()
    for _ in range(40):
        env.step(np.zeros(2, dtype=np.float32))
        tilt = max(tilt, tilt_degrees(robot.state().rotation))
    crept = np.linalg.norm(robot.state().position[:2] - stopped[:2])
    env.close()
    assert crept < 1e-3
    assert tilt < 1.0


def test_at_its_lowest_physics_rate_clutter_fly_comes_back_level():
    """A roll rate of +1 rad/s for 0.2 s and -1 rad/s for 0.2 s, then the hover command: 1 s later the airframe is
    level and still (at 5 Hz it was 11 degrees off and swinging at 3 rad/s, at 1-2 Hz it fell)."""
    from clutter_gym.clutter_fly import MIN_PHYSICS_HZ

    env = gym.make("ClutterFly-v1", physics_hz=MIN_PHYSICS_HZ, control_hz=30.0)
    env.reset(seed=0, options={"scene": {"obstacles": [], "start": [0.0, 0.0, 2.0, 0.7], "goal": [3.0, 3.0, 2.0]}})
    robot = env.unwrapped.robot
    hover = robot.hover_action(9.81).astype(np.float32)
    for roll, steps in ((1 / 3, 6), (-1 / 3, 6), (0.0, 45)):
        for _ in range(steps):
            env.step(hover + np.array([0.0, roll, 0.0, 0.0], dtype=np.float32))
    state = robot.state()
    env.close()
    assert tilt_degrees(state.rotation) < 0.5
    assert np.linalg.norm(state.angular_velocity) < 0.02


def test_at_its_lowest_physics_rate_the_panda_holds_still_after_a_move():
    """Joint velocity commands for 1 s, then zero: 2 s later no joint moves faster than 1e-4 rad/s (at 20 Hz one
    still moved at 2.5e-3 rad/s, at 10 Hz the arm sagged 0.1 rad under gravity)."""
    from clutter_gym.clutter_reach import MIN_PHYSICS_HZ

    env = gym.make("ClutterReach-v1", physics_hz=MIN_PHYSICS_HZ, control_hz=20.0, noise="none")
    env.reset(seed=0)
    move = np.array([0.5, -0.5, 0.5, 0.5, -0.5, 0.5, 0.5], dtype=np.float32)
    for action, steps in ((move, 20), (np.zeros(7, dtype=np.float32), 40)):
        for _ in range(steps):
            env.step(action)
    state = env.unwrapped.robot.state()
    env.close()
    assert np.abs(state.joint_velocity).max() < 1e-4
