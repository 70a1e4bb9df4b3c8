"""ClutterFly-v1 against gym-pybullet-drones' HoverAviary, side by side: kinematic, LIDAR and camera workloads.

Every workload runs in one process, one block each per round in alternating rounds, on uniform-random actions,
resetting where an episode ends as a training loop would (the reset counted). Each block keeps wall-clock and
process CPU time of ``step`` and of the resets apart; figures are medians over blocks (the first round's one-time
costs land in one block of several), and on a shared machine the CPU-time ones are the steadier. The ClutterFly-v1
variants share one seed and one action stream, so they fly the same trajectories and differ only in their sensors.
The peers are rebuilt call for call because gym-pybullet-drones is not installable here:
``benchmarks.peers.hover`` (HoverAviary, KIN observation, RPM action, its defaults: 240 Hz physics, 30 Hz control)
and ``benchmarks.peers.drones`` (the same env with its 64x48 RGB camera at 24 FPS, 48 Hz control).

The workloads: the KIN peer; ClutterFly-v1 at its defaults (IMU only; FCL clearance, contacts and the swept
audit every step); with a 16-channel x 64-ray LIDAR cast every control step (30 Hz) and at a 3D LIDAR's 10 Hz
(the rate is the noise profile's ``lidar.rate_hz``, set through ``noise={"lidar": {"rate_hz": 10}}`` on the clean
"none" profile: no noise is added, the scan is held between updates); with an 84x84 depth camera rendered every
control step, ray cast (the default) and by TinyRenderer; and the RGB peer. Then the ratios against the issue's
2x targets, what a camera frame costs either way, the IMU-only step against the raw pybullet work it needs
(``benchmarks.speed.fly_floor``, replayed on a twin of that env in the same rounds), what the LIDAR's rays cost,
whether the comparison held (the ClutterFly-v1 variants flew one flight, the floor's twin retraced it to the bit),
and a per-phase profile of the IMU-only step from a stopwatched copy of that env, run as one more block per round.

    python -m benchmarks.speed.fly_throughput [--steps 400] [--rounds 6]    # about 2 minutes on 2 shared cores
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import alternating_rounds, table_header
from benchmarks.peers.drones import make_drone_camera_workload
from benchmarks.peers.hover import HoverKinPeer, count_pybullet_calls
from benchmarks.speed.fly_floor import FlyFloor

LIDAR = {"sensors": ("imu", "lidar"), "lidar_channels": 16, "n_rays": 64}
#: label -> (factory, action shape)
WORKLOADS: dict[str, tuple[Callable[[], Any], tuple[int, ...]]] = {
    "peer: HoverAviary KIN (rebuilt)": (HoverKinPeer, (1, 4)),
    "ClutterFly-v1, IMU only": (lambda: gym.make("ClutterFly-v1"), (4,)),
    "ClutterFly-v1 + LIDAR 16x64 at 30 Hz": (lambda: gym.make("ClutterFly-v1", **LIDAR), (4,)),
    "ClutterFly-v1 + LIDAR 16x64 at 10 Hz": (
        lambda: gym.make("ClutterFly-v1", **LIDAR, noise={"lidar": {"rate_hz": 10.0}}), (4,)),
    "ClutterFly-v1 + depth camera 84x84 (rays)": (
        lambda: gym.make("ClutterFly-v1", sensors=("imu", "camera"), camera_size=(84, 84)), (4,)),
    "ClutterFly-v1 + depth camera 84x84 (TinyRenderer)": (
        lambda: gym.make("ClutterFly-v1", sensors=("imu", "camera"), camera_size=(84, 84), camera_renderer="tiny"),
        (4,)),
    "peer: HoverAviary 64x48 RGB (rebuilt)": (make_drone_camera_workload, (1, 4)),
}
KIN_PEER, IMU, LIDAR30, LIDAR10, DEPTH, DEPTH_TINY, RGB_PEER = WORKLOADS
FLY = (IMU, LIDAR30, LIDAR10, DEPTH, DEPTH_TINY)
TARGET = 2.0  # the "at least 2x the peer"
FLOOR = "floor: the raw pybullet work of an IMU-only step"


@dataclass
class Block:
    """One block of steps: seconds in ``step`` and in resets, wall-clock and process CPU, and the reset count."""

    steps: int
    step_wall: float
    reset_wall: float
    step_cpu: float
    reset_cpu: float
    resets: int

    @property
    def rate(self) -> float:
        """Steps per wall-clock second, resets included."""
        return self.steps / (self.step_wall + self.reset_wall)

    @property
    def cpu_rate(self) -> float:
        """Steps per CPU second, resets included."""
        return self.steps / (self.step_cpu + self.reset_cpu)

    @property
    def cpu_step_rate(self) -> float:
        """Steps per CPU second in ``step`` alone."""
        return self.steps / self.step_cpu


def run_block(env, actions: np.ndarray) -> Block:
    """Step ``env`` through ``actions``, resetting where an episode ends, timing steps and resets apart."""
    wall, cpu = time.perf_counter, time.process_time
    step_wall = reset_wall = step_cpu = reset_cpu = 0.0
    resets = 0
    for a in actions:
        t0, c0 = wall(), cpu()
        _, _, terminated, truncated, _ = env.step(a)
        t1, c1 = wall(), cpu()
        step_wall += t1 - t0
        step_cpu += c1 - c0
        if terminated or truncated:
            env.reset()
            reset_wall += wall() - t1
            reset_cpu += cpu() - c1
            resets += 1
    return Block(len(actions), step_wall, reset_wall, step_cpu, reset_cpu, resets)


def make_workloads(seed: int = 0) -> dict[str, tuple[Any, tuple[int, ...]]]:
    """Every workload, built and reset with ``seed``: label -> (env, shape)."""
    out = {}
    for label in WORKLOADS:
        factory, shape = WORKLOADS[label]
        env = factory()
        if isinstance(env, gym.Env):
            env.reset(seed=seed)
        else:  # the RGB peer's reset takes no seed: its scene and start are fixed
            env.reset()
        out[label] = (env, shape)
    return out


def pybullet_calls_per_step(env, shape: tuple[int, ...], rng: np.random.Generator, steps: int) -> float:
    """Mean pybullet calls per ``step`` over ``steps`` random actions (resets, outside the count, not counted)."""
    total = 0
    for _ in range(steps):
        a = rng.uniform(-1.0, 1.0, shape).astype(np.float32)
        result: list = []
        total += sum(count_pybullet_calls(lambda: result.extend(env.step(a))).values())
        if result[2] or result[3]:
            env.reset()
    return total / steps


def time_scans(env) -> PhaseTimers:
    """A CPU stopwatch around ``env``'s LIDAR read (the ray cast and its conversion), running from now on."""
    timers = PhaseTimers(time.process_time, active=True)
    for sensor in env.unwrapped.sensors:
        if sensor.name == "lidar":
            sensor.read = timers.wrap("scan", sensor.read)
    return timers


def action_rng(label: str, seed: int) -> np.random.Generator:
    """The action stream of a workload: every ClutterFly-v1 variant draws the same one, so that (reset with the
    same seed) they fly the same trajectory and differ only in their sensors; the two peers share another."""
    return np.random.default_rng([seed, 1 if label in FLY else 0])


def measure(workloads: dict[str, tuple[Any, tuple[int, ...]]], steps: int, rounds: int, seed: int = 0,
            profile: StepProfile | None = None, floor: FlyFloor | None = None) -> dict[str, list[Block]]:
    """``rounds`` alternating rounds of one ``steps``-step block per workload (and of ``profile`` and ``floor``, if
    given, so that their figures share the rounds' conditions); the blocks per workload, and the floor's under
    ``FLOOR`` (its step time only: its resets are untimed)."""
    rngs = {label: action_rng(label, seed) for label in workloads}

    def block(label: str) -> Callable[[], Block]:
        env, shape = workloads[label]
        return lambda: run_block(env, rngs[label].uniform(-1.0, 1.0, (steps, *shape)).astype(np.float32))

    measures: dict[str, Callable[[], Any]] = {label: block(label) for label in workloads}
    if floor is not None:
        floor_rng = action_rng(IMU, seed)  # the IMU-only workload's actions: the same flight

        def floor_block() -> Block:
            wall, cpu, resets = floor.run(floor_rng.uniform(-1.0, 1.0, (steps, 4)).astype(np.float32))
            return Block(steps, wall, 0.0, cpu, 0.0, resets)

        measures[FLOOR] = floor_block
    if profile is not None:
        measures["profile"] = lambda: profile.run(steps)
    figures = alternating_rounds(measures, rounds)
    figures.pop("profile", None)
    return figures


def one_flight(workloads: dict[str, tuple[Any, tuple[int, ...]]]) -> bool:
    """Whether the ClutterFly-v1 variants' robots are where the IMU-only one is, to the bit: they flew one flight
    (:func:`action_rng`)."""
    positions = [workloads[label][0].unwrapped.robot.state().position for label in FLY]
    return all(np.array_equal(p, positions[0]) for p in positions)


def median(blocks: list[Block], key: str) -> float:
    return statistics.median(getattr(b, key) for b in blocks)


# -- where an IMU-only step's time goes ---------------------------------------------------------------------------

class PhaseTimers:
    """Stopwatches (``clock``: wall by default) wrapped around an env's parts; they run only while ``active``."""

    def __init__(self, clock: Callable[[], float] = time.perf_counter, active: bool = False) -> None:
        self.seconds: Counter = Counter()
        self.calls: Counter = Counter()
        self.active = active
        self.clock = clock

    def wrap(self, name: str, fn: Callable) -> Callable:
        clock = self.clock

        def timed(*args, **kwargs):
            if not self.active:
                return fn(*args, **kwargs)
            t0 = clock()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[name] += clock() - t0
                self.calls[name] += 1

        return timed


#: (row, indent): top-level phases partition the step; indented rows are parts of the row above them
PHASES = (
    ("before_tick: rate loop, mixer, rotor forces (per tick)", 0),
    ("sim.step: pybullet stepSimulation (per tick)", 0),
    ("robot.state: batched pybullet state reads", 0),
    ("sim.contact_distances: pybullet contact points", 0),
    ("checker.check: FCL clearance, contacts, swept audit", 0),
    ("sync: move the FCL shapes", 1),
    ("search.lower_bounds: every pair's bound, in numpy", 1),
    ("search.nearest_pair: FCL distances in order of the bounds", 1),
    ("_contacts", 1),
    ("audit.count: the swept (tunneling) audit", 1),
    ("_observe: sensors, goal, proprioception", 0),
    ("sensors (IMU)", 1),
    ("task.observe", 1),
    ("robot.observe", 1),
    ("task.evaluate: reward terms, termination", 0),
)


class StepProfile:
    """ClutterFly-v1 (IMU only) with a CPU stopwatch around each part of its step (``PHASES``).

    Process CPU time, because wall time on a shared machine swings by 2x between runs; each stopwatch reading
    costs about 0.8 us (a system call), some 45 us over the ~30 timed calls of a step, mostly charged to the
    phases that hold them. Resets run with the stopwatches off.
    """

    def __init__(self, seed: int = 0) -> None:
        self.env = env = gym.make("ClutterFly-v1")
        env.reset(seed=seed)
        self.rng = action_rng(IMU, seed)  # the IMU-only workload's actions: the same trajectory
        self.steps, self.total = 0, 0.0
        u, t = env.unwrapped, PhaseTimers(time.process_time)
        self.timers = t
        names = [name for name, _ in PHASES]
        u.dynamics._before_tick = t.wrap(names[0], u.dynamics._before_tick)  # full physics: the per-tick hook
        u.sim.step = t.wrap(names[1], u.sim.step)
        u.robot.state = t.wrap(names[2], u.robot.state)
        u.sim.contact_distances = t.wrap(names[3], u.sim.contact_distances)
        u.checker.check = t.wrap(names[4], u.checker.check)
        c = u.checker
        for part, attr, name in zip((c, c.search, c.search, c, c.audit),
                                    ("sync", "lower_bounds", "nearest_pair", "_contacts", "count"), names[5:10],
                                    strict=True):
            setattr(part, attr, t.wrap(name, getattr(part, attr)))
        u._observe = t.wrap(names[10], u._observe)
        for sensor in u.sensors:
            for attr in ("read", "observe", "info"):
                setattr(sensor, attr, t.wrap(names[11], getattr(sensor, attr)))
        u.task.observe = t.wrap(names[12], u.task.observe)
        u.robot.observe = t.wrap(names[13], u.robot.observe)
        u.task.evaluate = t.wrap(names[14], u.task.evaluate)

    def run(self, steps: int) -> None:
        """``steps`` uniform-random-action steps, timed; episodes that end are reset untimed."""
        t, env = self.timers, self.env
        for a in self.rng.uniform(-1.0, 1.0, (steps, 4)).astype(np.float32):
            t.active = True
            t0 = time.process_time()
            _, _, terminated, truncated, _ = env.step(a)
            self.total += time.process_time() - t0
            t.active = False
            if terminated or truncated:
                env.reset()
        self.steps += steps

    def result(self) -> tuple[float, dict[str, tuple[float, float]]]:
        """The mean CPU seconds of ``env.step`` (gym.make's wrappers included), and per phase of ``PHASES`` plus
        ``"rest"`` (action checks, info dict, wrappers: the step less the top-level phases) its mean CPU seconds
        and calls per step."""
        t, n = self.timers, self.steps
        phases = {name: (t.seconds[name] / n, t.calls[name] / n) for name, _ in PHASES}
        top = sum(phases[name][0] for name, indent in PHASES if indent == 0)
        phases["rest: action checks, info dict, gym.make wrappers"] = (self.total / n - top, 0.0)
        return self.total / n, phases

    def close(self) -> None:
        self.env.close()


# -- report -------------------------------------------------------------------------------------------------------

def verdict(ratio: float) -> str:
    return f"{'met' if ratio >= TARGET else 'missed'} (target >= {TARGET:g}x)"


def report(blocks: dict[str, list[Block]], calls: dict[str, float], scans: dict[str, PhaseTimers]) -> str:
    """The table, the ratios against the targets, the IMU-only step against its floor (when ``blocks`` hold
    ``FLOOR``) and the LIDAR's cost; ``scans``: the LIDAR workloads' scan stopwatches (``time_scans``) over the
    same blocks."""
    peer_cpu = median(blocks[KIN_PEER], "cpu_rate")
    lines = [table_header("workload", "steps/s, wall", "steps per CPU-s", "steps per CPU-s, step() only",
                          "resets per 1,000 steps", "CPU ms per reset", "pybullet calls per step",
                          "vs KIN peer (CPU)")]
    for label, bs in blocks.items():
        if label == FLOOR:
            continue
        n = sum(b.steps for b in bs)
        resets = sum(b.resets for b in bs)
        reset_ms = 1e3 * sum(b.reset_cpu for b in bs) / resets if resets else math.nan
        lines.append(f"| {label} | {median(bs, 'rate'):,.0f} | {median(bs, 'cpu_rate'):,.0f} | "
                     f"{median(bs, 'cpu_step_rate'):,.0f} | {1e3 * resets / n:.0f} | {reset_ms:.1f} | "
                     f"{calls[label]:.1f} | {median(bs, 'cpu_rate') / peer_cpu:.2f}x |")

    def ratio(ours: str, peer: str, key: str) -> float:
        return median(blocks[ours], key) / median(blocks[peer], key)

    kin, kin_step = ratio(IMU, KIN_PEER, "cpu_rate"), ratio(IMU, KIN_PEER, "cpu_step_rate")
    cam, cam_step = ratio(DEPTH, RGB_PEER, "cpu_rate"), ratio(DEPTH, RGB_PEER, "cpu_step_rate")
    tiny, tiny_step = ratio(DEPTH_TINY, RGB_PEER, "cpu_rate"), ratio(DEPTH_TINY, RGB_PEER, "cpu_step_rate")
    frame_us = {label: 1e6 / median(blocks[label], "cpu_step_rate") - 1e6 / median(blocks[IMU], "cpu_step_rate")
                for label in (DEPTH, DEPTH_TINY)}
    lines += [
        "",
        f"Kinematic: ClutterFly-v1 (IMU) / HoverAviary KIN = {kin:.2f}x per CPU-s with resets, {kin_step:.2f}x "
        f"in step() alone: {verdict(kin)}.",
        f"Camera: ClutterFly-v1 (84x84 depth) / HoverAviary 64x48 RGB = {cam:.2f}x with resets, {cam_step:.2f}x "
        f"in step() alone: {verdict(cam)}. With TinyRenderer instead of the ray caster: {tiny:.2f}x with resets, "
        f"{tiny_step:.2f}x in step() alone. A frame costs {frame_us[DEPTH]:,.0f} us of CPU a step ray cast, "
        f"{frame_us[DEPTH_TINY]:,.0f} us rasterised (each over the IMU-only step).",
    ]
    if FLOOR in blocks:
        floor = median(blocks[FLOOR], "cpu_step_rate")
        lines.append(
            f"Floor: the raw pybullet work of the IMU-only step (its forces, ticks and state reads, replayed on a "
            f"twin) runs {floor:,.0f} steps per CPU-s; the step takes {ratio(FLOOR, IMU, 'cpu_step_rate'):.2f}x its "
            f"time.")
    imu_us = 1e6 / median(blocks[IMU], "cpu_step_rate")
    for label in (LIDAR30, LIDAR10):
        steps = sum(b.steps for b in blocks[label])
        n, seconds = scans[label].calls["scan"], scans[label].seconds["scan"]
        scan_us = 1e6 * seconds / n if n else math.nan
        lines.append(
            f"{label}: {median(blocks[label], 'cpu_rate'):,.0f} steps per CPU-s with resets, "
            f"{ratio(label, IMU, 'cpu_rate'):.2f}x the IMU-only env ({ratio(label, IMU, 'cpu_step_rate'):.2f}x in "
            f"step() alone, {1e6 / median(blocks[label], 'cpu_step_rate') - imu_us:,.0f} us a step more). "
            f"The rays: {n / steps:.2f} scans a step at {scan_us:,.0f} us of CPU per 1,024-ray scan (stopwatch "
            f"around the LIDAR's read), {1e6 * seconds / steps:,.0f} us a step.")
    return "\n".join(lines)


def profile_report(step_s: float, phases: dict[str, tuple[float, float]]) -> str:
    lines = [table_header("phase", "us per step", "share of step", "calls per step")]
    indents = dict(PHASES)
    for name, (seconds, calls) in phases.items():
        pad = "&nbsp;&nbsp;" * indents.get(name, 0)
        per_step = f"{calls:.0f}" if calls else ""
        lines.append(f"| {pad}{name} | {1e6 * seconds:,.0f} | {seconds / step_s:.0%} | {per_step} |")
    lines.append(f"| env.step, total | {1e6 * step_s:,.0f} | 100% | |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=400, help="steps per block")
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    started = time.perf_counter()
    workloads = make_workloads(seed=args.seed)
    rng = np.random.default_rng([args.seed, 2])
    calls, profile, floor = {}, None, None
    try:
        scans = {label: time_scans(workloads[label][0]) for label in (LIDAR30, LIDAR10)}
        profile, floor = StepProfile(args.seed), FlyFloor(args.seed)
        blocks = measure(workloads, args.steps, args.rounds, args.seed, profile, floor)
        for timers in scans.values():  # the rounds' scans only: the call counts below step the envs again
            timers.active = False
        same_flight, retraced = one_flight(workloads), floor.retraced()
        step_s, phases = profile.result()
        for label, (env, shape) in workloads.items():  # after the rounds, not to change their trajectories
            calls[label] = pybullet_calls_per_step(env, shape, rng, 30)
    finally:
        for env, _ in workloads.values():
            env.close()
        for part in (profile, floor):
            if part is not None:
                part.close()
    print(f"{args.rounds} alternating rounds of {args.steps} uniform-random-action steps per workload, resets "
          f"counted; medians over blocks\n")
    print(report(blocks, calls, scans))
    print(f"Checks: the ClutterFly-v1 variants {'flew' if same_flight else 'did NOT fly'} one flight; the floor's twin "
          f"{'retraced' if retraced else 'did NOT retrace'} the recorded flight to the bit.")
    print(f"\nWhere a ClutterFly-v1 (IMU only) step goes: a seventh workload in the same rounds, stopwatches around "
          f"each part (process CPU time, resets excluded; {profile.steps:,} steps)\n")
    print(profile_report(step_s, phases))
    print(f"\n(benchmark took {time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
