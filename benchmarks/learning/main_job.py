"""Learning benchmark: the main job (PPO on ClutterNav-v1 with its ppo.yml defaults) for several seeds.

Target (issue 5): at least 90% success and at most 5% collision episodes over 100 clean evaluation episodes,
within 15 minutes of wall time per seed on the 2-core reference machine. Prints, per seed, the wall time of the
training, the evaluation under the clean and nominal profiles, and the success / collision rates of the
training episodes at each quarter of the budget; writes ``OUT/learning.md`` and ``OUT/learning.png``.

    python -m benchmarks.learning.main_job --seeds 0 1 [--timesteps N] [--out out/learning] [--hyperparams F.yml]
        [--env-kwargs KEY=VALUE ...]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from benchmarks.harness import table_header
from clutter_gym.training.commands import add_settings_options, settings
from clutter_gym.training.figures import plt, save_figure
from clutter_gym.training.report import WINDOW, main_job, prepare_run, rolling_rate
from clutter_gym.util.atomic import write_text_atomically
from clutter_gym.util.machine import machine_state


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="ClutterNav-v1")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--timesteps", type=int, default=None)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--out", default="out/learning")
    add_settings_options(parser)
    args = parser.parse_args()
    out = Path(args.out)
    lines = [f"On {machine_state()}.", "", table_header("seed", "train wall (min)", "steps",
                          "training success / collision at 25 / 50 / 75 / 100% of budget", "eval `none` success",
                          "eval `none` collision", "eval `nominal` success", "eval `nominal` collision")]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for seed in args.seeds:
        t0 = time.perf_counter()
        run = prepare_run(args.env, out / f"seed{seed}", args.timesteps, seed, settings(args))
        main_job(run, out / f"seed{seed}", args.timesteps, args.episodes, progress=True)
        wall = time.perf_counter() - t0
        rows = run.read_episodes()
        steps = np.array([r["timestep"] for r in rows])
        success, collision = rolling_rate([r["success"] for r in rows]), rolling_rate([r["collision"] for r in rows])
        axes[0].plot(steps, success, label=f"seed {seed}")
        axes[1].plot(steps, collision, label=f"seed {seed}")
        quarters = [int(np.searchsorted(steps, q * steps[-1])) for q in (0.25, 0.5, 0.75)] + [len(steps) - 1]
        at = " / ".join(f"{success[min(i, len(steps) - 1)]:.0%}, {collision[min(i, len(steps) - 1)]:.0%}"
                        for i in quarters)
        ev = {p: json.loads((out / f"seed{seed}" / f"eval-{p}.json").read_text())["metrics"]
              for p in ("none", "nominal")}
        lines.append(f"| {seed} | {wall / 60:.1f} (incl. eval) | {int(steps[-1]):,} | {at} | "
                     f"{ev['none']['success_rate']['value']:.0%} | {ev['none']['collision_rate']['value']:.0%} | "
                     f"{ev['nominal']['success_rate']['value']:.0%} | {ev['nominal']['collision_rate']['value']:.0%} |")
        print(lines[-1], flush=True)
    for ax, title in zip(axes, ("success rate", "collision rate")):
        ax.set_title(f"{title} (last {WINDOW} training episodes)")
        ax.set_xlabel("env steps")
        ax.set_ylim(0, 1)
        ax.grid(alpha=0.3)
        ax.legend()
    save_figure(fig, out / "learning.png")
    write_text_atomically(out / "learning.md", "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
