"""Self-collision at the coarse levels, judged by their own shapes (as before) and confirmed with ``convex``'s (as
now, envs/collision/confirm.py): how often ClutterReach-v1 reports a cost under uniform random joint commands, how
often each level's self-collision verdict differs from ``convex``'s, and what ``checker.check`` and ``env.step``
cost, both ways in one run.

*before* is the rule before confirmation: the level's shapes decide, over an ACM sampled with those shapes
(``generate_acm`` at the level; ``spheres`` used ``mesh``'s). *now* is the env's checker as built today. Both
checkers have the env's settings and take turns in one env, episode by episode with the same seeds and actions, so
they see the same scenes and the same physics (a checker measures, it never acts). ``checker.check`` is then timed
on the recorded states, before and now taking turns episode by episode; figures are medians over rounds, in CPU
time. *extra* and
*missed* hits count the steps whose self-collision verdict differs from the ``convex`` checker's on the same state.

    python -m benchmarks.fidelity.coarse_self_collision [--episodes N] [--rounds R]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import table_header
from clutter_gym.collision import CollisionChecker, RobotCollisionModel, build_link_shapes, generate_acm
from clutter_gym.collision.fidelity import COARSE_LEVELS
from clutter_gym.urdf.geometry import load_collision_elements


def before_checker(env: gym.Env, level: str) -> CollisionChecker:
    """The env's checker as it was before confirmation: ``level``'s shapes decide over their own ACM."""
    u = env.unwrapped
    model = u.checker.model
    acm = generate_acm(u.robot.urdf_path, "mesh" if level == "spheres" else level)
    shapes = build_link_shapes(load_collision_elements(u.robot.urdf_path), level)
    padding = {s.link: float(p) for s, p in zip(model.shapes, model.padding)}
    c = u.checker
    return CollisionChecker(RobotCollisionModel(shapes, model.link_names, padding, acm), base_link=u.robot.base_link,
                            contact_tolerance=c.contact_tolerance, clearance_range=c.clearance_range,
                            swept_speed=c.swept_speed, dt=c.dt, fixed_links=(u.robot.base_link,))


def run_episodes(env: gym.Env, checkers: dict[str, CollisionChecker], episodes: int) -> dict[str, dict]:
    """Each episode once per checker (same seed, same uniform random joint commands, the checkers' order flipping
    every episode); per checker: whether each step had a cost, CPU seconds in env.step, and the recorded
    (obstacles, bodies, states) per episode."""
    u = env.unwrapped
    out = {name: {"cost": [], "step_s": 0.0, "episodes": []} for name in checkers}
    for episode in range(episodes):
        actions = np.random.default_rng(episode).uniform(-1.0, 1.0, size=(100, 7))
        for name in (list(checkers) if episode % 2 == 0 else list(checkers)[::-1]):
            checker = checkers[name]
            u.checker = checker
            env.reset(seed=episode)
            obstacles, bodies = u.arena.place(u.scene)
            states, record = [], out[name]
            for action in actions:
                t0 = time.process_time()
                _, _, terminated, truncated, info = env.step(action)
                record["step_s"] += time.process_time() - t0
                record["cost"].append(info["cost"] > 0.0)
                states.append(u.robot.state())
                if terminated or truncated:
                    break
            record["episodes"].append((obstacles, bodies, states))
    return out


def verdicts(checker: CollisionChecker, episodes: list) -> np.ndarray:
    out = []
    for obstacles, bodies, states in episodes:
        checker.set_scene(obstacles, bodies)
        out.extend(checker.check(s).self_collision is not None for s in states)
    return np.array(out)


def check_seconds(checkers: dict[str, CollisionChecker], episodes: list, rounds: int) -> dict[str, float]:
    """Median over ``rounds`` of the mean CPU seconds per ``checker.check`` on the recorded states. The checkers take
    turns episode by episode, in an order that flips every round; setting the scene is untimed. CPU time, not wall
    time: other processes on a shared machine then slow neither side."""
    figures: dict[str, list[float]] = {name: [] for name in checkers}
    n = sum(len(states) for _, _, states in episodes)
    for r in range(rounds):
        total = dict.fromkeys(checkers, 0.0)
        for obstacles, bodies, states in episodes:
            for name in (list(checkers) if r % 2 == 0 else list(checkers)[::-1]):
                checker = checkers[name]
                checker.set_scene(obstacles, bodies)
                t0 = time.process_time()
                for state in states:
                    checker.check(state)
                total[name] += time.process_time() - t0
        for name in checkers:
            figures[name].append(total[name] / n)
    return {name: float(np.median(f)) for name, f in figures.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=30, help="episodes (of up to 100 steps) per level")
    parser.add_argument("--rounds", type=int, default=9, help="timing rounds of checker.check")
    args = parser.parse_args()
    reference = gym.make("ClutterReach-v1", collision_fidelity="convex")
    rows = []
    for level in ("convex", *COARSE_LEVELS):
        env = gym.make("ClutterReach-v1", collision_fidelity=level)
        checkers = {"now": env.unwrapped.checker}
        if level != "convex":
            checkers["before"] = before_checker(env, level)
        runs = run_episodes(env, checkers, args.episodes)
        episodes = runs["now"]["episodes"]
        truth = verdicts(reference.unwrapped.checker, episodes)
        seen = {name: verdicts(c, episodes) for name, c in checkers.items()}
        check_us = {name: 1e6 * t for name, t in check_seconds(checkers, episodes, args.rounds).items()}
        for name in checkers:
            r = runs[name]
            rows.append((level, name, len(r["cost"]), np.mean(r["cost"]), seen[name].mean(), truth.mean(),
                         int(np.sum(seen[name] & ~truth)), int(np.sum(~seen[name] & truth)), check_us[name],
                         check_us[name] / check_us.get("before", check_us[name]), 1e3 * r["step_s"] / len(r["cost"])))
        env.close()
    reference.close()
    print(f"\nClutterReach-v1, uniform random joint commands, {args.episodes} seeded episodes per level; "
          f"checker.check: medians over {args.rounds} rounds, CPU time\n")
    print(table_header("level", "self-collision by", "steps", "cost", "self-collision", "convex's",
                       "extra hits", "missed hits", "check (us)", "check vs before", "env.step CPU (ms)"))
    for level, name, n, cost, seen, truth, extra, missed, us, ratio, step_ms in rows:
        print(f"| {level} | {name} | {n} | {cost:.1%} | {seen:.1%} | {truth:.1%} | {extra} | {missed} | {us:.0f} | "
              f"{ratio:.2f}x | {step_ms:.2f} |")


if __name__ == "__main__":
    main()
