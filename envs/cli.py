"""`clutter-gym` command line: ``demo``, ``profiles``, and the training commands ``train``, ``eval``, ``sweep``,
``report``."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from gymnasium.error import DependencyNotInstalled

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.noise.profiles import PROFILE_NAMES, profile_description, profile_table_markdown, resolve_noise
from clutter_gym.robots.registry import registered
from clutter_gym.training import commands as training_commands
from clutter_gym.training import require_train_extra
from clutter_gym.training.baselines import CascadedFlyer, PotentialFieldNavigator
from clutter_gym.training.commands import UserError, positive_int, user_errors
from clutter_gym.training.joint_planner import JointPlannerReacher
from clutter_gym.util.video import write_video


class Demo(NamedTuple):
    """An env's demo: its gym.make arguments, its scripted policy (made from the env after a reset) and the
    policy's name, the kind of robot the env drives (``--robot`` takes the registered robots of it), and what of
    the robot the frames ring (whose path length the summary gives as ``moved_m``)."""

    kwargs: dict[str, Any]
    make_policy: Callable[[gym.Env], Callable[[Any], np.ndarray]]
    name: str
    robot_kind: str
    focus: str


DEMOS = {
    "ClutterNav-v1": Demo({}, PotentialFieldNavigator.for_env, "scripted potential-field policy", "diff_drive",
                          "base"),
    "ClutterReach-v1": Demo({}, JointPlannerReacher, "scripted joint-space planner on the known layout, tracked",
                            "arm", "end effector"),
    "ClutterFly-v1": Demo({"subgoal_lookahead": 0.5}, lambda env: CascadedFlyer.for_env(env, "subgoal"),
                          "scripted position controller on the planned path", "multirotor", "airframe"),
}
DEMO_ENVS = tuple(DEMOS)
DEFAULT_DEMO = "ClutterNav-v1"
#: Without ``--seed``, the demo shows the first of these seeds whose layout the scripted policy has a plan for.
DEMO_SEEDS = range(10)


def demo(args: argparse.Namespace) -> dict:
    """Roll out the env's scripted policy, write a GIF and return the episode summary.

    Without ``args.seed``, layouts the policy has no plan for (``policy.no_plan``, the joint planner's) are
    skipped, and the summary says which and why; with it, that layout is shown, and the summary says why the robot
    holds still if it has no plan.

    Raises:
        UserError: the env refuses ``args.robot`` (unknown, or of another kind).
    """
    if args.agent:
        env_id, env, make_policy, policy_name, ringed = _trained_demo(args)
    else:
        env_id = args.env or DEFAULT_DEMO
        spec = DEMOS[env_id]
        kwargs = {**spec.kwargs, **({"robot": args.robot} if args.robot else {})}
        with user_errors(ValueError):
            env = gym.make(env_id, render_mode="rgb_array", noise=args.noise, **kwargs)
        make_policy, policy_name, ringed = spec.make_policy, spec.name, spec.focus
    try:
        skipped: dict[str, str] = {}
        seeds = DEMO_SEEDS if args.seed is None else [args.seed]
        for seed in seeds:
            obs, info = env.reset(seed=seed)
            policy = make_policy(env)  # a fresh one per layout: the demo of a seed is the same however reached
            action = policy(obs)
            no_plan = getattr(policy, "no_plan", None)
            if no_plan is None or seed == seeds[-1]:
                break
            skipped[str(seed)] = no_plan
        base = env.unwrapped
        frames = [env.render()]
        focus = np.asarray(base.robot.render_focus(base.robot.state())[0], dtype=float)
        episode_return, contact_steps, min_clearance, moved = 0.0, 0, info["min_clearance"], 0.0
        step_time, steps = 0.0, 0
        while True:
            t0 = time.perf_counter()
            obs, reward, terminated, truncated, info = env.step(action)
            step_time += time.perf_counter() - t0
            steps += 1
            episode_return += reward
            contact_steps += info["n_contacts"] > 0
            min_clearance = min(min_clearance, info["min_clearance"])
            now = np.asarray(base.robot.render_focus(base.robot.state())[0], dtype=float)
            moved, focus = moved + float(np.linalg.norm(now - focus)), now
            if steps % args.frame_every == 0:
                frames.append(env.render())
            if terminated or truncated or steps >= args.max_steps:
                break
            action = policy(obs)
        frames.append(env.render())
        gif = Path(args.out) / f"{env_id}-seed{seed}.gif"
        write_video(gif, frames, fps=env.metadata["render_fps"] / args.frame_every)
    finally:
        env.close()
    return {
        "env": env_id,
        "robot": base.robot.name,
        "policy": policy_name,
        "seed": seed,
        "skipped_seeds": skipped,
        "no_plan": getattr(policy, "no_plan", None),
        "noise": args.noise,
        "steps": steps,
        "return": round(episode_return, 3),
        "success": bool(info["is_success"]),
        "moved_m": round(moved, 3),
        "moved": ringed,
        "contact_steps": int(contact_steps),
        "min_clearance_m": round(float(min_clearance), 4),
        "steps_per_s": round(steps / step_time, 1) if step_time > 0 else None,
        "gif": str(gif),
    }


class _AgentPolicy:
    """A trained agent as the demo's policy: one observation in, one action out, its memory kept between calls."""

    def __init__(self, agent: Any) -> None:
        self.agent, self.state = agent, None

    def __call__(self, obs: Any) -> np.ndarray:
        action, self.state = self.agent.predict(obs, self.state)
        return action


def _trained_demo(args: argparse.Namespace) -> tuple[str, gym.Env, Callable[[gym.Env], Callable[[Any], np.ndarray]],
                                                      str, str]:
    """The env, policy maker, policy name and ringed part of a demo of the trained agent ``args.agent``.

    Raises:
        UserError: no such run or shipped agent, a run this version cannot load, or an ``--env`` or ``--robot``
            other than the agent's.
    """
    from clutter_gym.training import load
    from clutter_gym.training.run_dir import IncompatibleRunError

    with user_errors(FileNotFoundError, ValueError, IncompatibleRunError):
        agent = load(args.agent)
    env_id = agent.config.env_id
    if args.env not in (None, env_id):
        raise UserError(f"--env {args.env}: the agent {args.agent} drives {env_id}; leave --env out")
    if args.robot:
        raise UserError(f"--robot: the agent {args.agent} drives the robot it was trained on; leave --robot out")
    with user_errors(ValueError):
        env = agent.make_env(noise=args.noise, render_mode="rgb_array")
    return env_id, env, lambda env: _AgentPolicy(agent), f"trained agent {args.agent}", DEMOS[env_id].focus


def _print_demo(summary: dict) -> None:
    print(f"{summary['env']} ({summary['robot']}) seed {summary['seed']}, noise {summary['noise']!r}: "
          f"{summary['policy']}")
    for seed, why in summary["skipped_seeds"].items():
        print(f"  skipped seed   {seed}: {why}")
    if summary["no_plan"]:
        print(f"  no plan        {summary['no_plan']}: the robot holds still (without --seed the demo shows the "
              "first layout with a plan)")
    print(f"  steps          {summary['steps']}  ({'goal reached' if summary['success'] else 'goal not reached'})")
    print(f"  return         {summary['return']:.2f}")
    print(f"  moved          {summary['moved_m']:.2f} m ({summary['moved']})")
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
    p = sub.add_parser("demo", help="roll out a scripted policy (or a trained agent), write an episode GIF and print "
                                    "a summary",
                       description="Roll out a scripted policy (ClutterNav: a potential field; ClutterReach: a "
                                   "joint-space planner on the known layout and a path tracker; ClutterFly: a "
                                   "position controller on the planned path), write an episode GIF of the rgb_array "
                                   "frames (robot and goal ringed, the robot's trail drawn) and print a summary. "
                                   "Without --seed it shows the first layout the policy has a plan for, and says "
                                   "which it skipped and why. --agent shows a trained agent instead (a run folder, "
                                   "or pretrained/NAME for one shipped with the package).")
    p.add_argument("--env", choices=DEMO_ENVS, default=None, help=f"env id (default {DEFAULT_DEMO}, or the agent's)")
    p.add_argument("--agent", default=None, metavar="RUN",
                   help="show a trained agent instead of the scripted policy: a run folder, or pretrained/NAME, an "
                        "agent shipped with the package (needs the training extra)")
    p.add_argument("--seed", type=int, default=None,
                   help="reset seed (the layout); default: the first from 0 on whose layout the scripted policy has "
                        "a plan")
    p.add_argument("--robot", choices=registered(), default=None,
                   help="a registered robot of the env's kind (default: the env's own)")
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
    try:
        return _dispatch(parser, args)
    except KeyboardInterrupt as exc:  # Ctrl-C: training wrote a checkpoint first (TrainingInterrupted)
        print(f"clutter-gym {args.command}: {training_commands.interrupted(args, exc)}", file=sys.stderr, flush=True)
        return 130


def _dispatch(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    if args.command == "demo":
        try:
            if args.agent:
                require_train_extra("demo --agent")
            summary = demo(args)
        except DependencyNotInstalled as exc:
            parser.exit(1, f"clutter-gym demo: error: {exc}\n")
        except UserError as exc:
            parser.exit(2, f"clutter-gym demo: error: {exc}\n")
        if args.json:
            print(json.dumps(summary))
        else:
            _print_demo(summary)
    elif args.command == "profiles":
        profiles(args.name)
    else:
        try:
            require_train_extra("this command")
            return args.handler(args)
        except DependencyNotInstalled as exc:
            parser.exit(1, f"clutter-gym {args.command}: error: {exc}\n")
        except UserError as exc:
            parser.exit(2, f"clutter-gym {args.command}: error: {exc}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
