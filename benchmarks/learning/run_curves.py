"""Training curves of several runs side by side: validation success and collision rates, the rolling training
success rate, and PPO's action std and explained variance from each run's TensorBoard file. A distilled student's
validations are one per DAgger round; grey lines mark 100k, 500k and 2M steps where the axes reach them.

    python -m benchmarks.learning.run_curves --run "mapless=out/mapless" --run "field residual=out/residual" \
        --out docs/learning_sensors.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from clutter_gym.training.figures import plt, save_figure
from clutter_gym.training.report import rolling_rate
from clutter_gym.training.run_dir import RunDir

#: PPO's scalars, one panel each (a run that only distilled logs neither).
PPO_TAGS = ("train/std", "train/explained_variance")


def scalars(run: Path, tag: str) -> tuple[np.ndarray, np.ndarray]:
    """(steps, values) of one TensorBoard scalar of a run (empty when it was not logged)."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    steps, values = [], []
    for path in sorted((run / "tb").rglob("events.*")):
        acc = EventAccumulator(str(path), size_guidance={"scalars": 0})
        acc.Reload()
        if tag in acc.Tags()["scalars"]:
            steps += [e.step for e in acc.Scalars(tag)]
            values += [e.value for e in acc.Scalars(tag)]
    return np.array(steps), np.array(values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", action="append", required=True, metavar="NAME=RUN_DIR")
    parser.add_argument("--out", required=True, help="the PNG to write")
    args = parser.parse_args()
    ppo = [{tag: scalars(Path(spec.partition("=")[2]), tag) for tag in PPO_TAGS} for spec in args.run]
    panels = 4 if any(len(steps) for curves in ppo for steps, _ in curves.values()) else 2  # distillation only: 2
    fig, axes = plt.subplots(1, panels, figsize=(4 * panels, 3.6))
    for spec, curves in zip(args.run, ppo):
        name, _, folder = spec.partition("=")
        run = RunDir(folder)
        validations = run.read_validations()
        line, = axes[0].plot([r["step"] for r in validations], [r["success"] for r in validations], marker="o",
                             label=name)
        axes[0].plot([r["step"] for r in validations], [r["collision"] for r in validations], ls=":",
                     color=line.get_color())
        episodes = run.read_episodes()
        if episodes:
            axes[1].plot([r["timestep"] for r in episodes], rolling_rate(np.array([r["success"] for r in episodes])),
                         color=line.get_color())
        for ax, tag in zip(axes[2:], PPO_TAGS):
            ax.plot(*curves[tag], color=line.get_color())
    titles = ("validation success (solid), collisions (dotted)", "training success, rolling",
              "action std", "explained variance")
    for ax, title in zip(axes, titles):
        right = ax.get_xlim()[1]
        for mark in (100_000, 500_000, 2_000_000):
            if mark <= right:
                ax.axvline(mark, color="0.6", lw=0.8, zorder=0)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("env steps")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    print(save_figure(fig, Path(args.out)))


if __name__ == "__main__":
    main()
