"""How much of a privileged teacher a sensor-reading student could match: each teacher drives the student's env
(its shipped ``sensors`` settings, through the student's action interface, its continuous labels unbinned) on the
held-out layouts, when it plans on the whole layout (``planner``), on the obstacles its LIDAR has hit this
episode (``seen-map``: what a student with a memory could know), or on the hits of its current scan alone
(``in-range``: what a memoryless student sees). The gap between the last two rows and the first is the part of the
student-teacher gap that no imitation can close without memory, or at all.

    python -m benchmarks.learning.teacher_realisability --env ClutterNav-v1 --episodes 100
    python -m benchmarks.learning.teacher_realisability --env ClutterFly-v1 --episodes 50 --levels 0.05
    python -m benchmarks.learning.teacher_realisability --env ClutterReach-v1 --teachers line-up
    python -m benchmarks.learning.teacher_realisability --env ClutterReach-v1 --space action

``--space action`` drives the env's own actions instead of the student's interface (ClutterReach-v1's joint
velocities, where its ``planner`` teacher answers, against the student's hand controller). ``--astray SHARE
SPREAD`` rounds the teacher's labels to the student's bins and sends a ``SHARE`` of its steps up to ``SPREAD`` bins
astray in each entry: how much random imitation error the interface forgives.

    python -m benchmarks.learning.teacher_realisability --env ClutterFly-v1 --levels 0.05 --teachers planner \
        --episodes 50 --astray 0.3 2
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import clutter_gym  # noqa: F401  (registers the envs)
from benchmarks.harness import table_header
from clutter_gym.training.binned_actions import bin_values
from clutter_gym.training.config import EVAL_SEED, config_for, read_hyperparams_file, user_settings
from clutter_gym.training.evaluate import rollouts, summarize
from clutter_gym.training.residual import SubgoalResidual
from clutter_gym.training.teachers import TEACHERS, Teacher, TeacherLabels, make_teacher

LEVELS = {"ClutterNav-v1": ("obstacle_density", (0.05, 0.12, 0.2)), "ClutterFly-v1": ("obstacle_density", (0.05,)),
          "ClutterReach-v1": ("n_obstacles", (6,))}


class Astray(Teacher):
    """``teacher``'s labels rounded to ``bins`` bins, a ``share`` of them moved by up to ``spread`` bins in each
    entry (clipped to the ends, as a student's bins are), drawn from a generator of its own."""

    def __init__(self, teacher: Teacher, bins: int, share: float, spread: int) -> None:
        self.teacher, self.values, self.share, self.spread = teacher, bin_values(bins), share, spread
        self.rng = np.random.default_rng(0)

    def reset(self) -> None:
        self.teacher.reset()

    def __call__(self, obs: dict, info: dict) -> np.ndarray:
        label = np.asarray(self.teacher(obs, info))
        index = np.abs(self.values[None, :] - label[:, None]).argmin(axis=1)
        if self.rng.uniform() < self.share:
            index = np.clip(index + self.rng.integers(-self.spread, self.spread + 1, len(index)), 0,
                            len(self.values) - 1)
        return self.values[index].astype(np.float32)


def drive(env_id: str, teacher: str, level: tuple[str, float], episodes: int, noise: str = "none",
          interface: bool = True, astray: tuple[float, int] | None = None) -> dict:
    """The teacher's own episodes in the student's env at one clutter level, through the student's action
    interface (or, without ``interface``, the env's own actions), its labels sent ``astray`` (share, bins;
    :class:`Astray`) if given: the evaluation summary's metrics."""
    config = config_for(env_id, user_settings(read_hyperparams_file("sensors"), env_id))
    kwargs = {**config.make_kwargs(noise), level[0]: level[1], **TEACHERS[env_id][teacher]}
    env = gym.make(env_id, **kwargs)
    space = config.residual_space if interface else "action"
    if interface and config.uses_base:  # a waypoint the base controller follows, or the flyer's velocity
        env = SubgoalResidual(env, config.residual_gain, config.residual_space, config.residual_base)
    driver = make_teacher(env_id, teacher, env, space)
    if astray is not None:
        if not config.action_bins:
            raise SystemExit(f"--astray needs a student with action_bins; {env_id}'s sensors block has none")
        driver = Astray(driver, config.action_bins, *astray)
    labelled = TeacherLabels(env, driver, teacher_share=1.0)
    idle = np.zeros(env.action_space.shape, dtype=np.float32)  # ignored: the teacher drives every episode
    try:
        rows = rollouts(labelled, lambda obs, state: (idle, state), episodes, EVAL_SEED)
    finally:
        env.close()
    return summarize(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="ClutterNav-v1", choices=sorted(TEACHERS))
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--teachers", nargs="+", default=None, help="default: every teacher of the env")
    parser.add_argument("--levels", type=float, nargs="+", default=None, help="clutter levels (default: the env's)")
    parser.add_argument("--noise", default="none")
    parser.add_argument("--space", choices=("student", "action"), default="student",
                        help="the student's action interface, or the env's own actions")
    parser.add_argument("--astray", nargs=2, metavar=("SHARE", "SPREAD"), default=None,
                        help="round the labels to the student's bins and send SHARE of the steps up to SPREAD bins "
                             "astray")
    args = parser.parse_args()
    astray = None if args.astray is None else (float(args.astray[0]), int(args.astray[1]))
    key, levels = LEVELS[args.env]
    levels = args.levels or levels
    teachers = args.teachers or list(TEACHERS[args.env])
    t0 = time.perf_counter()
    print(f"{args.env}: teachers driving the student's env, {args.episodes} held-out layouts per cell (seeds "
          f"{EVAL_SEED}..), noise {args.noise!r}; success [95% Wilson interval] / collision episodes\n")
    print(table_header("teacher", *(f"{key} {v:g}" for v in levels)))
    for teacher in teachers:
        cells = []
        for value in levels:
            metrics = drive(args.env, teacher, (key, value), args.episodes, args.noise, args.space == "student",
                            astray)
            s, c = metrics["success_rate"], metrics["collision_rate"]
            cells.append(f"{s['value']:.0%} [{s['ci95'][0]:.0%}, {s['ci95'][1]:.0%}] / {c['value']:.0%}")
        print(f"| {teacher} | " + " | ".join(cells) + " |", flush=True)
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
