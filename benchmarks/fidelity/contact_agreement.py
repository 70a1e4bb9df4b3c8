"""How often FCL and pybullet disagree about contact, over contact-heavy random-walk rollouts of ClutterNav-v1.

FCL measures the exact geometry (cylinders as cylinders) at the pose after the step; pybullet reports the
contact points of its last narrow phase, with 64-gon prisms for cylinder obstacles and its own contact margins.
A disagreement is a step where exactly one engine sees a contact within ``contact_tolerance`` (1 mm).

    python -m benchmarks.fidelity.contact_agreement
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401
from benchmarks.harness import smooth_actions


def measure(steps: int, seed: int) -> dict[str, float]:
    env = gym.make("ClutterNav-v1")
    env.reset(seed=seed)
    counts = {"fcl": 0, "pybullet": 0, "fcl_only": 0, "pybullet_only": 0}
    clearance_at_disagreement = []
    for action in smooth_actions(np.random.default_rng(seed), steps):
        _, _, terminated, truncated, info = env.step(action)
        fcl_contact, pb_contact = info["n_contacts"] > 0, info["pybullet_contacts"] > 0
        counts["fcl"] += fcl_contact
        counts["pybullet"] += pb_contact
        counts["fcl_only"] += fcl_contact and not pb_contact
        counts["pybullet_only"] += pb_contact and not fcl_contact
        if fcl_contact != pb_contact:
            clearance_at_disagreement.append(info["min_clearance"])
        if terminated or truncated:
            env.reset()
    env.close()
    disagreements = counts["fcl_only"] + counts["pybullet_only"]
    return {**counts, "steps": steps, "disagreement_rate": disagreements / steps,
            "max_clearance_at_disagreement_mm": 1000 * max(clearance_at_disagreement, default=0.0)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=3)
    r = measure(parser.parse_args().steps, parser.parse_args().seed)
    print(f"{r['steps']} random-walk steps: contact in {r['fcl']} (FCL) / {r['pybullet']} (pybullet) steps")
    print(f"disagreement on {100 * r['disagreement_rate']:.2f}% of steps: FCL only {r['fcl_only']}, "
          f"pybullet only {r['pybullet_only']}; FCL clearance at a disagreement <= "
          f"{r['max_clearance_at_disagreement_mm']:.2f} mm")


if __name__ == "__main__":
    main()
