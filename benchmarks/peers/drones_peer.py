"""Steps/s of the rebuilt gym-pybullet-drones vision workload (``benchmarks.peers.drones``) alone.

Uniform-random RPM actions after an untimed warm-up, resetting where an episode ends as a training loop would
(the reset time counted); wall-clock and process CPU time are both kept.

Measured here (2 shared cores, pybullet 3.2.7, 2,000 random-action steps; the machine drifts by 15-20%
between runs minutes apart, so compare only figures from one run)
-----------------------------------------------------------------------------------------------------------
The default (landmark scene, 48 Hz): 356-369 steps/s counting ``step()`` alone, 277-287 steps/s with the
HoverAviary resets included (a random policy tips the drone past 0.4 rad in about 0.6 s, so about 70
resets of 22-23 ms each). Medians over interleaved blocks, per CPU second, ``step()`` alone (with resets):
landmarks at 24 Hz 183 (128), 48 Hz 364 (265), 240 Hz 1,730 (1,530); the samurai scene at 48 Hz 56 (37),
at 240 Hz 274 (220). The image is the bulk of the cost (about 5.6 ms each in the landmark scene and
35 ms in the samurai scene, against about 0.07 ms per physics substep), so steps/s follows images/step.
The ~237 steps/s quoted for the real peer on this machine lies between the 24 Hz and 48 Hz figures,
within about 20% of the 48 Hz figure with resets counted and of the samurai scene at 240 Hz.

    python -m benchmarks.peers.drones_peer    # --sweep: every allowed control rate in both scenes
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.harness import table_header
from benchmarks.peers.drone_body import DRONE_TRIANGLES
from benchmarks.peers.drones import DroneCameraWorkload, make_drone_camera_workload


def measure(workload: DroneCameraWorkload, steps: int, warmup: int, seed: int = 0) -> dict[str, float]:
    """Steps/s over ``steps`` uniform-random actions after ``warmup`` untimed ones, resetting when an episode
    ends as a gym training loop would (reset time counted, as it is in a training run's throughput).

    Wall-clock and process CPU time are both kept: on a shared machine the CPU-time figure is the steadier one.
    """
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, size=(warmup + steps, 1, 4)).astype(np.float32)
    workload.reset()
    for a in actions[:warmup]:
        _, _, terminated, truncated, _ = workload.step(a)
        if terminated or truncated:
            workload.reset()
    step_s = reset_s = step_cpu = reset_cpu = 0.0
    resets, images0 = 0, workload.images
    for a in actions[warmup:]:
        t0, c0 = time.perf_counter(), time.process_time()
        _, _, terminated, truncated, _ = workload.step(a)
        t1, c1 = time.perf_counter(), time.process_time()
        step_s, step_cpu = step_s + t1 - t0, step_cpu + c1 - c0
        if terminated or truncated:
            workload.reset()
            reset_s, reset_cpu = reset_s + time.perf_counter() - t1, reset_cpu + time.process_time() - c1
            resets += 1
    return {
        "steps_per_s": steps / (step_s + reset_s),
        "steps_per_s_without_resets": steps / step_s,
        "steps_per_cpu_s": steps / (step_cpu + reset_cpu),
        "steps_per_cpu_s_without_resets": steps / step_cpu,
        "resets": resets,
        "reset_ms": 1e3 * reset_s / max(resets, 1),
        "images_per_step": (workload.images - images0) / steps,
    }


def _row(scene: str, ctrl_freq: int, r: dict[str, float]) -> str:
    n = 240 // ctrl_freq
    return (f"| {scene} | {ctrl_freq} Hz ({n} substep{'s' if n > 1 else ''}) | {r['images_per_step']:.2f} | "
            f"{r['steps_per_s_without_resets']:,.0f} | {r['steps_per_s']:,.0f} | "
            f"{r['steps_per_cpu_s_without_resets']:,.0f} | {r['resets']} x {r['reset_ms']:.0f} ms |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--warmup", type=int, default=200)
    parser.add_argument("--ctrl-freq", type=int, default=48, help="24, 48, 120 or 240 (Hz)")
    parser.add_argument("--scene", choices=("rl", "vision_aviary"), default="rl")
    parser.add_argument("--drone-triangles", type=int, default=DRONE_TRIANGLES)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sweep", action="store_true", help="every allowed control rate, both scenes")
    args = parser.parse_args()
    configs = ([(scene, f) for scene in ("rl", "vision_aviary") for f in (24, 48, 120, 240)] if args.sweep
               else [(args.scene, args.ctrl_freq)])
    print(f"gym-pybullet-drones HoverAviary(obs=RGB) workload, reconstructed: 240 Hz physics, 64x48 TinyRenderer "
          f"image at 24 FPS, shadow=1; {args.steps} uniform-random-action steps after {args.warmup} warm-up\n")
    print(table_header("scene", "control", "images/step", "steps/s, step() only", "steps/s, resets included",
                       "steps per CPU-s, step() only", "resets"))
    for scene, ctrl_freq in configs:
        workload = make_drone_camera_workload(ctrl_freq=ctrl_freq, scene=scene,
                                              drone_triangles=args.drone_triangles)
        try:
            r = measure(workload, args.steps, args.warmup, args.seed)
        finally:
            workload.close()
        print(_row(scene, ctrl_freq, r), flush=True)
    print(f"\ndrone visual mesh: {workload.drone_triangles} triangles (cf2.dae stand-in)")


if __name__ == "__main__":
    main()
