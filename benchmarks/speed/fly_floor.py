"""The raw pybullet work one ClutterFly-v1 step needs, replayed on a twin env's client: the floor the env's step is
measured against, as ``benchmarks.speed.throughput`` measures ClutterNav-v1 against its own.

A recorder env flies the action stream through ``env.step`` (untimed) and records, every physics tick, the rotor
forces and the body wrench its robot applied. A twin env, built and reset with the same seed, replays them through
bare pybullet calls, timed: per tick the base-state read any inner loop needs (``getBasePositionAndOrientation``,
``getBaseVelocity``), the four rotor forces, the body torque and ``stepSimulation``; per step the base-state read
a robot state needs. The twin is reset (untimed) where the recorder's episodes ended, so it flies the same scenes
and, with the same forces on deterministic physics, the same trajectory through the same contacts. Everything else
the env does is the overhead the ratio measures: the inner loop's arithmetic, FCL clearance, contacts and the swept
audit, the path-distance reward, observations and Gymnasium's wrappers.
"""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np

from benchmarks.harness import pb


class FlyFloor:
    """A recorder and a twin ClutterFly-v1 (IMU only, its defaults) with one seed."""

    def __init__(self, seed: int = 0) -> None:
        self.recorder, self.twin = gym.make("ClutterFly-v1"), gym.make("ClutterFly-v1")
        self.recorder.reset(seed=seed)
        self.twin.reset(seed=seed)
        self._ticks: list[tuple] = []
        actuation = self.recorder.unwrapped.sim.actuation
        apply_forces, apply_wrench = actuation.apply_base_forces, actuation.apply_base_wrench

        def forces(body, forces, points):
            self._ticks.append((forces, points))
            apply_forces(body, forces, points)

        def wrench(body, force, torque):
            self._ticks[-1] += (force, torque)
            apply_wrench(body, force, torque)

        actuation.apply_base_forces, actuation.apply_base_wrench = forces, wrench

    def run(self, actions: np.ndarray) -> tuple[float, float, int]:
        """Record ``actions`` on the recorder, then replay them on the twin: (wall s, CPU s) of the replay's steps,
        and the episodes that ended."""
        self._ticks.clear()
        ends = []
        for i, a in enumerate(actions):
            _, _, terminated, truncated, _ = self.recorder.step(a)
            if terminated or truncated:
                self.recorder.reset()
                ends.append(i)
        u = self.twin.unwrapped
        cid, body, substeps = u.sim.client_id, u.robot.body, u.substeps
        world, link = pb.WORLD_FRAME, pb.LINK_FRAME
        wall = cpu = 0.0
        ticks, previous = iter(self._ticks), 0
        last = [] if ends and ends[-1] == len(actions) - 1 else [len(actions) - 1]
        for end in [*ends, *last]:  # the steps of one episode (or of its part in these actions), then its reset
            t0, c0 = time.perf_counter(), time.process_time()
            for k in range((end - previous + 1) * substeps):
                forces, points, force, torque = next(ticks)
                pb.getBasePositionAndOrientation(body, physicsClientId=cid)
                pb.getBaseVelocity(body, physicsClientId=cid)
                for f, p in zip(forces, points):
                    pb.applyExternalForce(body, -1, f, p, link, physicsClientId=cid)
                if any(force):
                    position, _ = pb.getBasePositionAndOrientation(body, physicsClientId=cid)
                    pb.applyExternalForce(body, -1, force, position, world, physicsClientId=cid)
                pb.applyExternalTorque(body, -1, torque, world, physicsClientId=cid)
                pb.stepSimulation(physicsClientId=cid)
                if k % substeps == substeps - 1:  # a step's state read
                    pb.getBasePositionAndOrientation(body, physicsClientId=cid)
                    pb.getBaseVelocity(body, physicsClientId=cid)
            wall += time.perf_counter() - t0
            cpu += time.process_time() - c0
            if end in ends:
                self.twin.reset()
            previous = end + 1
        return wall, cpu, len(ends)

    def retraced(self) -> bool:
        """Whether the twin's base (position, rotation, velocity) is the recorder's to the bit: the replay flew the
        recorded flight."""
        flown, replayed = self.recorder.unwrapped.robot.state(), self.twin.unwrapped.robot.state()
        return all(np.array_equal(a, b) for a, b in ((flown.position, replayed.position),
                                                     (flown.rotation, replayed.rotation),
                                                     (flown.linear_velocity, replayed.linear_velocity)))

    def close(self) -> None:
        self.recorder.close()
        self.twin.close()
