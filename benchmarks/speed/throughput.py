"""ClutterNav-v1 steps/s and reset time against the raw pybullet work it needs, measured side by side.

The floor replays, through bare pybullet calls on a twin env's client, what one ClutterNav step cannot avoid:
the motor command, the ``stepSimulation`` calls, the three batched state reads and one ``rayTestBatch``. The
twin starts from the same seed, gets the same wheel commands and is reset (untimed) at the same steps, so the
deterministic physics retraces the env's trajectory exactly and both pay for the same contacts and the same
beams (cast, as the env casts them, in the LIDAR link's frame). Everything else the env does (FCL
clearance and contacts, the pybullet contact cross-check, sensor and reward maths, Gymnasium's wrappers) is the
overhead the ratio measures. Env and floor run in alternating blocks so that machine noise hits both alike;
figures are medians over blocks. If panda-gym is installed, PandaReach-v3 joins the alternation as the peer.

    python -m benchmarks.speed.throughput    # or: python3 tasks.py bench
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import EnvRunner, pb, smooth_actions, table_header
from clutter_gym.sim import RAY_INVISIBLE_GROUP
from clutter_gym.training.baselines import PotentialFieldNavigator
from clutter_gym.util.quiet import quiet_c_output


class Floor:
    """The raw pybullet calls one ClutterNav step needs, replayed on a twin env's client."""

    def __init__(self, twin: gym.Env) -> None:
        self.twin = twin
        u = twin.unwrapped
        self.cid, self.robot, self.config = u.sim.client_id, u.robot.body, u.robot.config
        self.wheels, self.links, self.substeps = u.robot.wheel_joints, u.robot.tracked_links, u.substeps
        lidar = next(s for s in u.sensors if s.name == "lidar")
        self.ray_starts, self.ray_ends = lidar.ray_starts, lidar.ray_ends
        self.lidar_link = u.robot.link_index[lidar.config.link]
        self.torques = [self.config.max_wheel_torque] * 2

    def run(self, actions: np.ndarray, ends: list[int]) -> float:
        cid, robot, c = self.cid, self.robot, self.config
        half, total, ends = 0.5 * c.wheel_separation, 0.0, set(ends)
        for i, a in enumerate(actions):
            v, w = float(a[0]) * c.max_linear_speed, float(a[1]) * c.max_angular_speed
            wheels = [(v - w * half) / c.wheel_radius, (v + w * half) / c.wheel_radius]
            t0 = time.perf_counter()
            pb.setJointMotorControlArray(robot, self.wheels, pb.VELOCITY_CONTROL, targetVelocities=wheels,
                                         forces=self.torques, physicsClientId=cid)
            for _ in range(self.substeps):
                pb.stepSimulation(physicsClientId=cid)
            pb.getBasePositionAndOrientation(robot, physicsClientId=cid)
            pb.getBaseVelocity(robot, physicsClientId=cid)
            pb.getLinkStates(robot, self.links, computeLinkVelocity=1, computeForwardKinematics=1,
                             physicsClientId=cid)
            pb.rayTestBatch(self.ray_starts, self.ray_ends, parentObjectUniqueId=robot,
                            parentLinkIndex=self.lidar_link, numThreads=1,
                            collisionFilterMask=-1 ^ RAY_INVISIBLE_GROUP, physicsClientId=cid)
            total += time.perf_counter() - t0
            if i in ends:
                self.twin.reset()
        return total


def make_peer() -> EnvRunner | None:
    """panda-gym's PandaReach-v3, if installed."""
    try:
        with quiet_c_output():
            import panda_gym  # noqa: F401

            return EnvRunner(gym.make("PandaReach-v3"), seed=0)
    except ImportError:
        return None


def reset_times(env: gym.Env, n: int, warmup: int) -> np.ndarray:
    for _ in range(warmup):  # fills the body pool; a long training run lives in this regime
        env.reset()
    out = np.empty(n)
    for i in range(n):
        t0 = time.perf_counter()
        env.reset()
        out[i] = time.perf_counter() - t0
    return out


def scenario(name: str, seed: int, rounds: int, steps: int, peer: EnvRunner | None) -> dict[str, float]:
    """Alternate env, floor (and peer) blocks; medians over blocks."""
    env, twin = gym.make("ClutterNav-v1"), gym.make("ClutterNav-v1")
    runner = EnvRunner(env, seed)
    twin.reset(seed=seed)
    floor = Floor(twin)
    rng = np.random.default_rng(seed)
    navigator = PotentialFieldNavigator.for_env(env)
    rows: dict[str, list[float]] = {"env": [], "floor": [], "ratio": [], "peer": []}
    for _ in range(rounds):
        if name == "navigator":
            seconds, actions, ends = runner.run(lambda obs, i: navigator(obs), steps)
        else:
            walk = smooth_actions(rng, steps)
            seconds, actions, ends = runner.run(lambda obs, i, walk=walk: walk[i], steps)
        floor_seconds = floor.run(actions, ends)
        rows["env"].append(steps / seconds)
        rows["floor"].append(steps / floor_seconds)
        rows["ratio"].append(seconds / floor_seconds)
        if peer is not None:
            uniform = rng.uniform(-1, 1, size=(steps, *peer.env.action_space.shape))
            rows["peer"].append(steps / peer.run(lambda obs, i, uniform=uniform: uniform[i], steps)[0])
    same = np.array_equal(env.unwrapped.robot.state().position, twin.unwrapped.robot.state().position)
    assert same, "the floor did not retrace the env's trajectory: the comparison would be unfair"
    env.close()
    twin.close()
    return {key: statistics.median(v) for key, v in rows.items() if v}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=8, help="alternating env/floor blocks per scenario")
    parser.add_argument("--steps", type=int, default=1000, help="steps per block")
    parser.add_argument("--resets", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", help="also write the figures to this JSON file")
    args = parser.parse_args()

    peer = make_peer()
    figures: dict[str, object] = {
        name: scenario(name, args.seed, args.rounds, args.steps, peer) for name in ("navigator", "random-walk")
    }
    resets = reset_times(gym.make("ClutterNav-v1"), args.resets, warmup=200) * 1e3
    figures["reset_ms"] = {"median": float(np.median(resets)), "p95": float(np.percentile(resets, 95))}

    print(f"ClutterNav-v1 defaults (64-beam LIDAR + IMU + FCL clearance and contacts), one process, "
          f"{args.rounds} alternating blocks of {args.steps} steps per scenario\n")
    print(table_header("scenario", "env steps/s", "raw pybullet floor steps/s", "env time / floor time"))
    for name, label in (("navigator", "scripted navigator (drives around clutter)"),
                        ("random-walk", "random walk (frequent contact)")):
        f = figures[name]
        print(f"| {label} | {f['env']:,.0f} | {f['floor']:,.0f} | {f['ratio']:.3f} |")
    print(f"\nreset with a new layout ({args.resets} resets after 200 warm-up): median "
          f"{figures['reset_ms']['median']:.2f} ms, p95 {figures['reset_ms']['p95']:.2f} ms")
    peers = [figures[n].get("peer") for n in ("navigator", "random-walk") if "peer" in figures[n]]
    if peers:
        print(f"panda-gym PandaReach-v3 in the same alternation: {statistics.median(peers):,.0f} steps/s")
    else:
        print("panda-gym not installed (pip install '.[bench]'): no peer figure")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(figures, f, indent=2)


if __name__ == "__main__":
    main()
