"""The swept audit (``info["tunneling"]``) against the physics' own ticks, on seeded random-action runs.

The audit sees the robot at two control steps and judges the motion between them. The physics ticks several times
in between: after every tick this script measures the robot against the scene with a second checker (same shapes,
tolerance and padding; no sweep). A step *touched unseen* when a (link, obstacle) pair came within the contact
tolerance at one of its ticks, yet was clear at the step's end and at the step before: that is what the audit should
flag. Printed: such steps, those the audit flagged, the audit's flags at steps without one, and of the missed ones
how many end in contact anyway (their cost is charged) and how many do not (bounces within one step).

    python -m benchmarks.hard_cases.audit_vs_ticks [--env ClutterFly-v1] [--steps 600] [--env-kwargs '{}']
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.collision import CollisionChecker, RobotCollisionModel


def reference_checker(checker: CollisionChecker) -> CollisionChecker:
    """A checker of the same shapes and settings that measures without sweeping."""
    model = checker.model
    fixed = tuple(link for link in model.links if link not in checker.links)
    padding = float(model.padding.max()) if len(model.padding) else 0.0
    return CollisionChecker(RobotCollisionModel(model.shapes, model.link_names, padding), checker._base_link,
                            contact_tolerance=checker.contact_tolerance, clearance_range=checker.clearance_range,
                            swept_speed=np.inf, dt=checker.dt, fixed_links=fixed)


def run(env_id: str, steps: int, seed: int, kwargs: dict) -> dict[str, list[int]]:
    """Step numbers: ``touched`` (touched unseen, by the ticks), ``flagged`` (by the audit), ``ended_in_contact``
    (touched steps that end with some contact)."""
    env = gym.make(env_id, **kwargs)
    core = env.unwrapped
    reference = reference_checker(core.checker)
    set_scene = core.checker.set_scene

    def both(obstacles, bodies):  # the reference follows every scene the env's checker gets
        reference.set_scene(obstacles, bodies)
        set_scene(obstacles, bodies)

    core.checker.set_scene = both
    step_physics, ticks = core.sim.step, []

    def pairs() -> set[tuple[str, int]]:
        return {(c.link, c.obstacle) for c in reference.check(core.robot.state()).contacts}

    def one_tick_at_a_time(n: int = 1) -> None:
        for _ in range(n):
            step_physics(1)
            ticks.append(pairs())

    core.sim.step = one_tick_at_a_time
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    before = pairs()
    out: dict[str, list[int]] = {"touched": [], "flagged": [], "ended_in_contact": []}
    for t in range(steps):
        ticks.clear()
        _, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
        end = ticks[-1]
        if set().union(*ticks[:-1]) - end - before:
            out["touched"].append(t)
            if info["n_contacts"]:
                out["ended_in_contact"].append(t)
        if info["tunneling"]:
            out["flagged"].append(t)
        before = end
        if terminated or truncated:
            env.reset()
            before = pairs()
    env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="ClutterFly-v1")
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--env-kwargs", default="{}", help="JSON keyword arguments for the env")
    args = parser.parse_args()
    r = run(args.env, args.steps, args.seed, json.loads(args.env_kwargs))
    touched, flagged = set(r["touched"]), set(r["flagged"])
    missed = sorted(touched - flagged)
    charged = [t for t in missed if t in r["ended_in_contact"]]
    print(f"{args.env} {args.env_kwargs}, {args.steps} seeded random steps (seed {args.seed}):")
    print(f"touched unseen by the ticks: {len(touched)}; flagged by the audit: {len(touched & flagged)}; "
          f"flags without a touch: {len(flagged - touched)} {sorted(flagged - touched)}")
    print(f"missed: {len(missed)} {missed}; of them ending in contact (cost charged): {len(charged)}")


if __name__ == "__main__":
    main()
