"""How a waypoint student's episodes end, and how far its waypoint is from its teacher's along the way.

A student with ``residual_space: waypoint`` (ClutterNav-v1's bearing, ClutterFly-v1's azimuth and elevation) is
rolled out on held-out layouts (seeds 1,000,000..) in an env made with the planner's subgoal as well, which the
student never reads: at every step the planner teacher's waypoint is the subgoal's azimuth. Each episode reports
how it ended, the distance to the goal at its end, the share of its steps spent nearly still, and the median angle
between the student's azimuth and the teacher's, over the episode and over its last 50 steps. A failed episode
whose student keeps far from the teacher's direction while it stands still is imitation error in front of an
obstacle, not a crash or a slow arrival. On ClutterFly-v1 each row also has the elevation's gap over the last 50
steps and whether a piece of a wall (the volume's walls with one opening) is within :data:`WALL_NEAR` of the drone
at the end.

    python -m benchmarks.learning.waypoint_diagnosis --run RUN --episodes 20 [--obstacle-density 0.05]
"""

from __future__ import annotations

import argparse
import math

import gymnasium as gym
import numpy as np

from clutter_gym.training import load
from clutter_gym.training.config import EVAL_SEED
from clutter_gym.training.teachers import flyer_waypoint

#: m/s: a speed under this is "nearly still"
STILL = 0.1
#: m ahead on the planned path that the teacher's waypoint points at (the teachers' own lookahead)
LOOKAHEAD = 0.5
#: m: a wall piece this near the drone at an episode's end counts as "at a wall"
WALL_NEAR = 1.0


def teacher_azimuth(env_id: str, subgoal: np.ndarray) -> float:
    """The planner's waypoint azimuth, radians: ClutterNav's subgoal is (distance, sin, cos), ClutterFly's (x, y, z)."""
    if env_id == "ClutterNav-v1":
        return math.atan2(float(subgoal[1]), float(subgoal[2]))
    return float(flyer_waypoint(subgoal)[0]) * math.pi


def speed(env_id: str, velocity: np.ndarray) -> float:
    """m/s: ClutterNav's velocity entry is (forward speed, yaw rate), ClutterFly's starts with the linear velocity."""
    return abs(float(velocity[0])) if env_id == "ClutterNav-v1" else float(np.linalg.norm(velocity[:3]))


def teacher_elevation(subgoal: np.ndarray) -> float:
    """ClutterFly's planner waypoint elevation, radians."""
    return float(flyer_waypoint(subgoal)[1]) * math.pi / 2


def at_wall(env: gym.Env) -> bool:
    """Whether a piece of one of ClutterFly's walls (a box as thick as the volume's walls) is within
    :data:`WALL_NEAR` of the drone."""
    u = env.unwrapped
    position = np.asarray(u.robot_state().position)
    thickness = u.task.spec.wall_thickness
    return any(o.shape == "box" and math.isclose(min(o.size[:2]), thickness) and o.distance3d(position) < WALL_NEAR
               for o in u.scene.obstacles)


def episode(agent, env: gym.Env, seed: int) -> dict:
    """One episode's row (see the module docstring)."""
    chosen: list[np.ndarray] = []
    residual = agent._residual  # the student's waypoint is the action its residual interface receives
    fly = agent.config.env_id == "ClutterFly-v1"

    def spy(raw, action):
        chosen.append(np.asarray(action, dtype=float).copy())
        return residual(raw, action)

    agent._residual = spy
    try:
        obs, _ = env.reset(seed=seed)
        state, gaps, lifts, still, steps, collided = None, [], [], 0, 0, False
        while True:
            target = teacher_azimuth(agent.config.env_id, obs["subgoal"])
            action, state = agent.predict({k: v for k, v in obs.items() if k != "subgoal"}, state)
            gaps.append(abs((chosen[-1][0] * math.pi - target + math.pi) % (2 * math.pi) - math.pi))
            if fly:
                lifts.append(abs(chosen[-1][1] * math.pi / 2 - teacher_elevation(obs["subgoal"])))
            obs, _, terminated, truncated, info = env.step(action)
            steps += 1
            still += speed(agent.config.env_id, obs["velocity"]) < STILL
            collided |= info["cost"] > 0
            if terminated or truncated:
                break
    finally:
        agent._residual = residual
    goal_distance = float(obs["goal"][3] if fly else obs["goal"][0])
    row = {"seed": seed, "success": bool(info["is_success"]), "collision": bool(collided), "steps": steps,
           "end_distance": goal_distance, "still": still / steps, "gap": math.degrees(float(np.median(gaps))),
           "gap_last50": math.degrees(float(np.median(gaps[-50:])))}
    if fly:
        row.update(elevation_last50=math.degrees(float(np.median(lifts[-50:]))), wall=at_wall(env))
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", required=True, help="a waypoint student's run folder")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--obstacle-density", type=float, default=None,
                        help="the layouts' clutter (default: the run's)")
    args = parser.parse_args()
    agent = load(args.run)
    if agent.config.residual_space != "waypoint":
        raise SystemExit(f"{args.run} is not a waypoint student (residual_space {agent.config.residual_space!r})")
    density = {} if args.obstacle_density is None else {"obstacle_density": args.obstacle_density}
    env = gym.make(agent.config.env_id, **{**agent.config.make_kwargs(), "subgoal_lookahead": LOOKAHEAD, **density})
    rows = [episode(agent, env, EVAL_SEED + i) for i in range(args.episodes)]
    env.close()
    fly = "wall" in rows[0]
    extra = " elevation gap (median, last 50 steps) | at a wall at the end |" if fly else ""
    print("| seed | ends | steps | goal distance at the end (m) | nearly still | waypoint gap to the teacher "
          f"(median, last 50 steps) |{extra}\n|---|---|---|---|---|---|" + "---|---|" * fly)
    for r in rows:
        ends = "success" if r["success"] else "collision" if r["collision"] else "timeout"
        cells = f" {r['elevation_last50']:.0f} deg | {'yes' if r['wall'] else 'no'} |" if fly else ""
        print(f"| {r['seed']} | {ends} | {r['steps']} | {r['end_distance']:.2f} | {r['still']:.0%} | "
              f"{r['gap']:.0f} deg, {r['gap_last50']:.0f} deg |{cells}")
    for name, group in (("finished", [r for r in rows if r["success"]]),
                        ("failed", [r for r in rows if not r["success"]])):
        if group:
            print(f"\n{name}: {len(group)} of {len(rows)}; median goal distance at the end "
                  f"{np.median([r['end_distance'] for r in group]):.2f} m, nearly still "
                  f"{np.median([r['still'] for r in group]):.0%} of steps, waypoint gap "
                  f"{np.median([r['gap'] for r in group]):.0f} deg (last 50 steps "
                  f"{np.median([r['gap_last50'] for r in group]):.0f} deg)", end="")
            if fly:
                print(f", elevation gap {np.median([r['elevation_last50'] for r in group]):.0f} deg (last 50 "
                      f"steps), {sum(r['wall'] for r in group)} at a wall at the end", end="")
    print()

if __name__ == "__main__":
    main()
