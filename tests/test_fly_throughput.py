"""``python -m benchmarks.speed.fly_throughput`` for two short rounds and ``python -m benchmarks.peers.hover`` (the
facts its HoverAviary KIN peer reproduces), run as a user runs them: no timing is asserted."""

from __future__ import annotations

import math
import re

import pytest
from helpers import markdown_rows, run_benchmark

#: seed 5's random actions end an IMU-only episode at step 39: the rounds' 60 steps replay a reset on the floor
FLIGHT = ("--steps", "30", "--rounds", "2", "--seed", "5")
WORKLOADS = 7


@pytest.fixture(scope="module")
def peer():
    run = run_benchmark("benchmarks.peers.hover")
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


@pytest.fixture(scope="module")
def bench():
    run = run_benchmark("benchmarks.speed.fly_throughput", *FLIGHT)
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


def test_peer_observation_has_gym_pybullet_drones_kin_shape(peer):
    """12 kinematic values and 15 buffered 4-value actions (half a second at 30 Hz), for one drone."""
    assert "observation: shape (1, 72) (upstream's (1, 72)), space (1, 72); info {'answer': 42}" in peer
    step = re.search(r"the newest action is the observation's last 4 values: True; finite: True; reward (\S+), "
                     r"terminated False, truncated False", peer)
    assert step and 0.0 <= float(step.group(1)) <= 2.0, peer


def test_peer_makes_the_upstream_pybullet_calls(peer):
    """Per step 8 ticks of 4 rotor forces, the yaw torque and stepSimulation, then one kinematics read."""
    calls = re.search(r"pybullet calls per step: 51 \(upstream's 51\): (.*); per reset: 11 \(upstream's 11\)", peer)
    assert calls, peer
    assert dict((name, int(n)) for name, n in (c.split() for c in calls.group(1).split(", "))) == {
        "applyExternalForce": 32, "applyExternalTorque": 8, "stepSimulation": 8, "getBasePositionAndOrientation": 1,
        "getEulerFromQuaternion": 1, "getBaseVelocity": 1}


def test_peer_truncation_rules(peer):
    """Hover RPMs hold the drone still until the 8 s limit (the step whose counter before it passes 1,920 ticks);
    a roll command ends the episode on the 0.4 rad tilt rule long before."""
    hover = re.search(r"hover RPMs .*: truncated after (\d+) steps, terminated before: False; z (\S+) m", peer)
    assert hover and int(hover.group(1)) == 242 and abs(float(hover.group(2)) - 0.1125) < 1e-3, peer
    roll = re.search(r"roll command .*: truncated after (\d+) steps, terminated before: False; .* roll (\S+) rad", peer)
    assert roll and int(roll.group(1)) < 60 and abs(float(roll.group(2))) > 0.4, peer


def workload_rows(bench: str) -> dict[str, list[str]]:
    table = bench.split("\n\n")[1]
    return {cells[0]: cells[1:] for cells in markdown_rows(table)[1:]}


def test_every_workload_gives_finite_positive_rates(bench):
    rows = workload_rows(bench)
    assert len(rows) == WORKLOADS
    for label, cells in rows.items():
        for rate in cells[:3]:  # wall-clock, per CPU-s, per CPU-s in step() alone
            assert math.isfinite(float(rate.replace(",", ""))) and float(rate.replace(",", "")) > 0.0, (label, cells)
    assert rows["peer: HoverAviary KIN (rebuilt)"][5] == "51.0"  # pybullet calls per step: the peer's upstream 51
    assert float(rows["ClutterFly-v1, IMU only"][5]) > 0.0
    assert all(line in bench for line in ("\nKinematic:", "\nCamera:", "\nFloor:"))


def test_the_lidar_is_cast_at_its_rate(bench):
    """A 30 Hz LIDAR scans on every control step (and once more at a reset), a 10 Hz one on some."""
    found = re.findall(r"\+ LIDAR 16x64 at (\d+) Hz: .* The rays: ([\d.]+) scans a step at ([\d,]+) us", bench)
    scans = {hz: (float(per_step), float(us.replace(",", ""))) for hz, per_step, us in found}
    assert 1.0 <= scans["30"][0] <= 1.05 and scans["30"][1] > 0.0, scans
    assert 0.0 < scans["10"][0] < 1.0, scans


def test_the_variants_fly_one_flight_and_the_floor_replays_it_across_a_reset(bench):
    """Every ClutterFly-v1 variant draws one action stream, so they fly the same flight and differ only in their
    sensors; the floor's twin, given the recorder's forces tick by tick and reset where its episodes ended, retraces
    the flight to the bit."""
    assert float(workload_rows(bench)["ClutterFly-v1, IMU only"][3]) > 0.0  # resets per 1,000 steps: one was replayed
    assert "Checks: the ClutterFly-v1 variants flew one flight; the floor's twin retraced the recorded flight" in bench


def test_phase_profile_accounts_for_the_step(bench):
    profile = markdown_rows(bench.split("Where a ClutterFly-v1 (IMU only) step goes")[1])[1:]
    total = float(profile[-1][1].replace(",", ""))
    top = [cells for cells in profile[:-2] if not cells[0].startswith("&nbsp;")]
    assert total > 0.0 and all(float(cells[1].replace(",", "")) > 0.0 for cells in top)
    rest = profile[-2]
    assert rest[0].startswith("rest") and float(rest[1].replace(",", "")) >= 0.0  # the top phases fit in the step
    assert top[0][3] == "8" and top[1][3] == "8"  # 8 physics ticks a step
