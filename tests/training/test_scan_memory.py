"""The LIDAR memory kept by dead reckoning: an obstacle it saw stays where it was as the robot moves, and the agent
keeps the same memory from plain observations as training gives the policy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clutter_gym.training.scan_memory import ScanMemory, memory_for

ANGLES = -math.pi + 2 * math.pi * np.arange(8) / 8  # beams every 45 degrees, beam 4 straight ahead


def _scan(beam: int, distance: float, max_range: float = 3.5) -> np.ndarray:
    ranges = np.ones(8)
    ranges[beam] = distance / max_range
    return ranges


def test_a_return_ahead_stays_put_while_the_robot_drives_towards_it_then_turns_away():
    memory = ScanMemory("polar", ANGLES, 3.5, dt=0.1, reach=6.0)
    first = memory.update(_scan(4, 2.0), None)  # an obstacle 2 m ahead
    assert first[4] == pytest.approx(2.0 / 6.0)
    for _ in range(10):  # 1 m forwards at 1 m/s, seeing nothing any more
        out = memory.update(np.ones(8), np.array([1.0, 0.0]))
    assert out[4] == pytest.approx(1.0 / 6.0)  # still there, now 1 m ahead
    for _ in range(10):  # a quarter turn left in place: pi/2 rad/s for 1 s
        out = memory.update(np.ones(8), np.array([0.0, math.pi / 2]))
    assert out[2] == pytest.approx(1.0 / 6.0, abs=1e-6)  # now on the right (beam 2: -90 degrees)
    assert np.count_nonzero(out < 1) == 1


def test_the_grid_puts_a_return_in_the_cell_it_lies_in():
    memory = ScanMemory("grid", ANGLES, 3.5, dt=0.1, cells=8, cell=0.5)
    grid = memory.update(_scan(5, 1.2), None).reshape(8, 8)  # beam 5: 45 degrees left, 0.85 m ahead and left
    assert np.argwhere(grid).tolist() == [[2, 2]]  # row 2: 0.5..1.0 m ahead of centre; column 2: 0.5..1.0 m left


def test_returns_seen_twice_are_kept_once_and_a_new_episode_forgets():
    memory = ScanMemory("polar", ANGLES, 3.5, dt=0.1)
    for _ in range(5):
        memory.update(_scan(4, 2.0), np.zeros(2))
    assert len(memory.points) == 1
    memory.reset()
    assert len(memory.points) == 0
    assert np.all(memory.update(np.ones(8), None) == 1.0)


def test_the_memory_needs_a_2d_lidar(make_env):
    with pytest.raises(ValueError, match="needs a ClutterNav env with a 2D LIDAR"):
        memory_for(make_env("ClutterNav-v1", sensors=["imu"]), "polar")
    with pytest.raises(ValueError, match="scan_memory must be one of"):
        ScanMemory("map", ANGLES, 3.5, 0.1)
