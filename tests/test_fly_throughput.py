"""benchmarks.speed.fly_throughput and its HoverAviary KIN peer, run for a few steps: no timing is asserted."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.peers.hover import CALLS_PER_RESET, CALLS_PER_STEP, KIN_SHAPE, HoverKinPeer, count_pybullet_calls
from benchmarks.speed.fly_floor import FlyFloor
from benchmarks.speed.fly_throughput import (
    FLOOR,
    FLY,
    IMU,
    KIN_PEER,
    LIDAR10,
    LIDAR30,
    PHASES,
    WORKLOADS,
    make_workloads,
    measure,
    phase_profile,
    pybullet_calls_per_step,
    report,
    time_scans,
)


@pytest.fixture
def peer():
    env = HoverKinPeer()
    yield env
    env.close()


def test_peer_observation_has_gym_pybullet_drones_kin_shape(peer):
    """12 kinematic values and 15 buffered 4-value actions (half a second at 30 Hz), for one drone."""
    assert KIN_SHAPE == (1, 72)
    obs, info = peer.reset(seed=0)
    assert obs.shape == peer.observation_space.shape == KIN_SHAPE and info == {"answer": 42}
    action = np.full((1, 4), 0.5, dtype=np.float32)
    obs, reward, terminated, truncated, _ = peer.step(action)
    assert obs.shape == KIN_SHAPE and np.all(np.isfinite(obs))
    assert np.array_equal(obs[0, -4:], action[0])  # the newest action is the buffer's last entry
    assert 0.0 <= reward <= 2.0 and not terminated and not truncated


def test_peer_makes_the_upstream_pybullet_calls(peer):
    """Per step 8 ticks of 4 rotor forces, the yaw torque and stepSimulation, then one kinematics read."""
    peer.reset(seed=0)
    calls = count_pybullet_calls(lambda: peer.step(np.zeros((1, 4), dtype=np.float32)))
    assert calls == {"applyExternalForce": 32, "applyExternalTorque": 8, "stepSimulation": 8,
                     "getBasePositionAndOrientation": 1, "getEulerFromQuaternion": 1, "getBaseVelocity": 1}
    assert sum(calls.values()) == CALLS_PER_STEP == 51
    assert sum(count_pybullet_calls(lambda: peer.reset()).values()) == CALLS_PER_RESET


def test_peer_truncation_rules(peer):
    """Hover RPMs hold the drone still until the 8 s limit (the step whose counter before it passes 1,920 ticks);
    a roll command ends the episode on the 0.4 rad tilt rule long before."""
    peer.reset(seed=0)
    steps, truncated = 0, False
    while not truncated:
        obs, _, terminated, truncated, _ = peer.step(np.zeros((1, 4), dtype=np.float32))
        steps += 1
        assert not terminated
    assert steps == 242 and abs(obs[0, 2] - 0.1125) < 1e-3
    peer.reset()
    roll = np.array([[-1.0, -1.0, 1.0, 1.0]], dtype=np.float32)  # right rotors slow, left fast: roll right
    for steps in range(1, 100):
        obs, _, _, truncated, _ = peer.step(roll)
        if truncated:
            break
    assert truncated and steps < 60 and abs(obs[0, 3]) > 0.4


def test_every_workload_gives_finite_positive_rates():
    workloads = make_workloads()
    assert list(workloads) == list(WORKLOADS)
    floor = FlyFloor(0)
    try:
        calls = {label: pybullet_calls_per_step(env, shape, np.random.default_rng(0), 2)
                 for label, (env, shape) in workloads.items()}
        scans = {label: time_scans(workloads[label][0]) for label in (LIDAR30, LIDAR10)}
        blocks = measure(workloads, steps=3, rounds=2, floor=floor)
        # one action stream for every ClutterFly-v0 variant: the same flight, whatever the sensors
        positions = [workloads[label][0].unwrapped.robot.state().position for label in FLY]
        assert all(np.array_equal(p, positions[0]) for p in positions)
    finally:
        for env, _ in workloads.values():
            env.close()
        floor.close()
    assert calls[KIN_PEER] == CALLS_PER_STEP and calls[IMU] > 0
    for label, bs in blocks.items():
        assert len(bs) == 2, label
        for b in bs:
            for rate in (b.rate, b.cpu_rate, b.cpu_step_rate):
                assert math.isfinite(rate) and rate > 0.0, (label, b)
    assert scans[LIDAR30].calls["scan"] == 6  # a 30 Hz LIDAR scans on every one of the 2 x 3 steps
    assert 1 <= scans[LIDAR10].calls["scan"] <= 6 and scans[LIDAR30].seconds["scan"] > 0.0
    text = report(blocks, calls, scans)
    assert text.count("\n| ") == len(WORKLOADS) and "Kinematic:" in text and "Camera:" in text
    assert FLOOR in blocks and "Floor:" in text


def test_the_floor_replays_the_recorded_flight_exactly():
    """The twin, given the recorder's forces tick by tick and reset where its episodes ended, retraces its flight:
    the same scenes, the same physics, the same final state to the bit."""
    floor = FlyFloor(0)
    try:
        wall, cpu, resets = floor.run(np.random.default_rng(3).uniform(-1.0, 1.0, (300, 4)).astype(np.float32))
        flown, replayed = floor.recorder.unwrapped.robot.state(), floor.twin.unwrapped.robot.state()
    finally:
        floor.close()
    assert resets >= 1 and wall > 0.0 and cpu > 0.0
    for a, b in ((flown.position, replayed.position), (flown.rotation, replayed.rotation),
                 (flown.linear_velocity, replayed.linear_velocity)):
        np.testing.assert_array_equal(a, b)


def test_phase_profile_accounts_for_the_step():
    step_s, phases = phase_profile(steps=4)
    assert step_s > 0.0
    top = [phases[name][0] for name, indent in PHASES if indent == 0]
    assert all(s > 0.0 for s in top)
    assert sum(top) <= step_s
    assert phases[PHASES[0][0]][1] == 8 and phases[PHASES[1][0]][1] == 8  # 8 physics ticks a step
