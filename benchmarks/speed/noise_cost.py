"""What noise costs: ClutterNav-v1 steps/s under each noise profile, measured side by side in one run.

Each profile runs twice. "As specified" is the profile itself: its slower LIDARs (5-5.5 Hz for low-cost and
harsh) cast fewer rays, and its action noise and dynamics randomisation change the trajectory and so the contact
work. "Sensor noise only" keeps the profile's sensor noise and latencies but updates every sensor each control
step and turns action noise and dynamics randomisation off: the robot then retraces the clean env's trajectory
exactly (the script checks this), so the difference to "none" is the cost of the noise chains and delay lines
alone. All envs drive the same random-walk actions from the same seed, in blocks whose order is shuffled each
round; figures are medians over blocks. The end-to-end difference is within the machine's noise (+-15 us/step
here), so the script also times the noise code itself inside the "sensor noise only" runs: every noise function
and delay line, wrapped with a stopwatch, as a share of the step.

    python -m benchmarks.speed.noise_cost
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
import clutter_gym.sensors.imu
import clutter_gym.sensors.lidar
from benchmarks.harness import EnvRunner, smooth_actions, table_header
from clutter_gym.noise.profiles import PROFILE_NAMES
from clutter_gym.sensors.timing import SampleHoldDelay

SENSOR_NOISE_ONLY = {
    "lidar": {"rate_hz": 0.0},
    "imu": {"rate_hz": 0.0},
    "action": {"latency_steps": 0, "sigma": 0.0},
    "dynamics": {"friction_range": 0.0, "restitution_max": 0.0, "mass_range": 0.0, "motor_range": 0.0},
}


#: (object, attribute) of everything the noise adds to a step: noise functions, delay lines, action channel
NOISE_CODE = [
    (clutter_gym.sensors.lidar, "apply_lidar_noise"),
    (clutter_gym.sensors.lidar, "angle_offsets"),
    (clutter_gym.sensors.imu, "apply_imu_noise"),
    (SampleHoldDelay, "due"),
    (SampleHoldDelay, "push"),
]


class Stopwatch:
    """Accumulates the time spent in the wrapped functions while ``active``."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self.active = False

    @contextlib.contextmanager
    def wrapping(self, targets):
        originals = [(obj, name, getattr(obj, name)) for obj, name in targets]
        for obj, name, fn in originals:
            setattr(obj, name, self._timed(fn))
        try:
            yield self
        finally:
            for obj, name, fn in originals:
                setattr(obj, name, fn)

    def _timed(self, fn):
        def timed(*args, **kwargs):
            if not self.active:
                return fn(*args, **kwargs)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - t0

        return timed


def configs() -> dict[str, dict]:
    out: dict[str, dict] = {}
    for name in PROFILE_NAMES:
        out[name] = {"profile": name}
        if name != "none":
            out[f"{name}, sensor noise only"] = {"profile": name, **SENSOR_NOISE_ONLY}
    return out


def measure(rounds: int, steps: int, seed: int) -> tuple[dict[str, float], dict[str, float]]:
    """Median steps/s per config (:func:`configs`), and the noise code's median share of the step for the
    "sensor noise only" configs."""
    runners = {label: EnvRunner(gym.make("ClutterNav-v1", noise=spec), seed) for label, spec in configs().items()}
    rates: dict[str, list[float]] = {label: [] for label in runners}
    shares: dict[str, list[float]] = {label: [] for label in runners if label.endswith("sensor noise only")}
    rng = np.random.default_rng(seed)
    labels = list(runners)
    with Stopwatch().wrapping(NOISE_CODE) as watch:
        for _ in range(rounds):
            walk = smooth_actions(rng, steps)
            for k in rng.permutation(len(labels)):  # a new order each round: no env always follows the same one
                label = labels[k]
                watch.seconds, watch.active = 0.0, label in shares
                seconds, _, _ = runners[label].run(lambda obs, i, walk=walk: walk[i], steps)
                rates[label].append(steps / seconds)
                if label in shares:
                    shares[label].append(watch.seconds / seconds)
    clean_position = runners["none"].env.unwrapped.robot.state().position
    for label, runner in runners.items():
        if label.endswith("sensor noise only"):
            same = np.array_equal(runner.env.unwrapped.robot.state().position, clean_position)
            assert same, f"{label} left the clean trajectory: the comparison would not isolate the noise"
        runner.env.close()
    return ({label: statistics.median(v) for label, v in rates.items()},
            {label: statistics.median(v) for label, v in shares.items()})


def lidar_deviation_m(profile: str, steps: int = 300, seed: int = 0) -> float:
    """Mean absolute difference (m) between the LIDAR observation under ``profile``'s sensor noise and the clean
    one, on the same trajectory (the "sensor noise only" settings keep it the clean env's); dropouts and spurious
    returns count in full."""
    spec = {"profile": profile, **SENSOR_NOISE_ONLY} if profile != "none" else "none"
    clean, noisy = gym.make("ClutterNav-v1"), gym.make("ClutterNav-v1", noise=spec)
    scale = next(s for s in clean.unwrapped.sensors if s.name == "lidar").config.max_range  # obs = range / scale
    clean.reset(seed=seed)
    noisy.reset(seed=seed)
    deviations = []
    for a in smooth_actions(np.random.default_rng(seed), steps):
        a_obs, *_ = clean.step(a)
        b_obs, *_ = noisy.step(a)
        deviations.append(scale * float(np.abs(a_obs["lidar"] - b_obs["lidar"]).mean()))
    clean.close()
    noisy.close()
    return float(np.mean(deviations))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=8)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    rates, shares = measure(args.rounds, args.steps, args.seed)
    base = rates["none"]
    print(f"ClutterNav-v1 defaults (64-beam LIDAR + IMU), {args.rounds} alternating blocks of {args.steps} "
          "random-walk steps\n")
    print(table_header("noise", "steps/s", "us/step", "step time vs none", "noise code, share of the step"))
    for label, rate in rates.items():
        share = f"{shares[label]:.1%}" if label in shares else ""
        print(f"| {label} | {rate:,.0f} | {1e6 / rate:.0f} | {base / rate - 1:+.1%} | {share} |")


if __name__ == "__main__":
    main()
