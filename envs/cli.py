"""`clutter-gym` command line: ``demo``, ``profiles``, and the training commands ``train``, ``eval``, ``sweep``,
``report``."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import typing
from pathlib import Path

import gymnasium as gym
from gymnasium.error import DependencyNotInstalled

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.noise.profiles import PROFILE_NAMES, profile_description, profile_table_markdown, resolve_noise
from clutter_gym.training import commands as training_commands
from clutter_gym.training import require_train_extra
from clutter_gym.training.baselines import CascadedFlyer, PotentialFieldNavigator
from clutter_gym.training.commands import UserError, positive_int
from clutter_gym.training.joint_planner import JointPlannerReacher
from clutter_gym.util.video import write_video

#: Per demo env: its gym.make arguments, the scripted policy for the env, and the policy's name.
DEMOS = {
    "ClutterNav-v0": ({}, PotentialFieldNavigator.for_env, "scripted potential-field policy"),
    "ClutterReach-v0": ({}, JointPlannerReacher, "scripted joint-space planner on the known layout, tracked"),
    "ClutterFly-v0": ({"subgoal_lookahead": 0.5}, lambda env: CascadedFlyer.for_env(env, "subgoal"),
                      "scripted position controller on the planned path"),
}
DEMO_ENVS = tuple(DEMOS)


def demo(args: argparse.Namespace) -> dict:
    """Roll out the env's scripted policy, write a GIF and return the episode summary."""
    kwargs, make_policy, name = DEMOS[args.env]
    env = gym.make(args.env, render_mode="rgb_array", noise=args.noise, **kwargs)
    try:
        obs, info = env.reset(seed=args.seed)
        policy = make_policy(env)
        frames = [env.render()]
        episode_return, contact_steps, min_clearance = 0.0, 0, info["min_clearance"]
        step_time, steps, terminated, truncated = 0.0, 0, False, False
        while not (terminated or truncated) and steps < args.max_steps:
            action = policy(obs)
            t0 = time.perf_counter()
            obs, reward, terminated, truncated, info = env.step(action)
            step_time += time.perf_counter() - t0
            steps += 1
            episode_return += reward
            contact_steps += info["n_contacts"] > 0
            min_clearance = min(min_clearance, info["min_clearance"])
            if steps % args.frame_every == 0:
                frames.append(env.render())
        frames.append(env.render())
        gif = Path(args.out) / f"{args.env}-seed{args.seed}.gif"
        write_video(gif, frames, fps=env.metadata["render_fps"] / args.frame_every)
    finally:
        env.close()
    return {
        "env": args.env,
        "policy": name,
        "seed": args.seed,
        "noise": args.noise,
        "steps": steps,
        "return": round(episode_return, 3),
        "success": bool(info["is_success"]),
        "contact_steps": int(contact_steps),
        "min_clearance_m": round(float(min_clearance), 4),
        "steps_per_s": round(steps / step_time, 1) if step_time > 0 else None,
        "gif": str(gif),
    }


def _print_demo(summary: dict) -> None:
    print(f"{summary['env']} seed {summary['seed']}, noise {summary['noise']!r}: {summary['policy']}")
    print(f"  steps          {summary['steps']}  ({'goal reached' if summary['success'] else 'goal not reached'})")
    print(f"  return         {summary['return']:.2f}")
    print(f"  contact steps  {summary['contact_steps']}")
    print(f"  min clearance  {summary['min_clearance_m']:.3f} m")
    print(f"  env steps/s    {summary['steps_per_s']} (env.step only, in a short run with rendering in between;"
          " python3 tasks.py bench measures throughput)")
    print(f"  episode GIF    {summary['gif']}")


class Parser(argparse.ArgumentParser):
    """argparse whose errors are one line, ``clutter-gym train: error: ...``, with exit status 2."""

    def error(self, message: str) -> typing.NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="clutter-gym", description="Robots in cluttered worlds: a scripted demo, the noise "
                    "profiles, and PPO training, evaluation, sim-to-real sweeps and the main job's report.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("demo", help="roll out a scripted policy, write an episode GIF and print a summary",
                       description="Roll out a scripted policy (ClutterNav: a potential field; ClutterReach: a "
                                   "joint-space planner on the known layout and a path tracker; ClutterFly: a "
                                   "position controller on the planned path), write an episode GIF of the rgb_array "
                                   "frames (robot and goal ringed, the robot's trail drawn) and print a summary.")
    p.add_argument("--env", choices=DEMO_ENVS, default="ClutterNav-v0", help="env id")
    p.add_argument("--seed", type=int, default=0, help="reset seed (the layout)")
    p.add_argument("--max-steps", type=positive_int, default=600, help="stop the episode after this many steps")
    p.add_argument("--frame-every", type=positive_int, default=2, help="keep every k-th frame in the GIF")
    p.add_argument("--out", default="out/demo", help="folder for the GIF")
    p.add_argument("--noise", choices=PROFILE_NAMES, default="none", help="sensor/actuation noise profile")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p = sub.add_parser("profiles", help="list the noise profiles; print one's parameters; print the markdown table "
                                        "of docs/noise.md",
                       description="List the noise profiles and their parameters, or print one profile's resolved "
                                   "parameters as JSON.")
    p.add_argument("name", nargs="?", choices=PROFILE_NAMES, help="print this profile's resolved parameters as JSON")
    training_commands.add_parsers(sub)
    return parser


def profiles(name: str | None) -> None:
    if name is not None:
        print(json.dumps(resolve_noise(name).to_dict(), indent=2))
        return
    for profile in PROFILE_NAMES:
        print(f"- `{profile}`: {profile_description(profile)}")
    print()
    print(profile_table_markdown())


def main(argv: list[str] | None = None) -> int:
    """The command line; a reader that stops reading (``clutter-gym profiles | head``) ends it quietly."""
    try:
        return _run(argv)
    except BrokenPipeError:
        # Python's recipe: point stdout at devnull so that the flush at exit does not raise again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _run(argv: list[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "demo":
        summary = demo(args)
        if args.json:
            print(json.dumps(summary))
        else:
            _print_demo(summary)
    elif args.command == "profiles":
        profiles(args.name)
    else:
        try:
            require_train_extra(f"clutter-gym {args.command}")
            return args.handler(args)
        except DependencyNotInstalled as exc:
            parser.exit(1, f"clutter-gym {args.command}: error: {exc}\n")
        except UserError as exc:
            parser.exit(2, f"clutter-gym {args.command}: error: {exc}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
