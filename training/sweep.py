"""The sim-to-real sweep: train under each noise profile (several seeds), evaluate every run under every profile.

A *cell* is one (train profile, seed): it trains a run (resuming it if a killed sweep left it half done) and
evaluates it under each evaluation profile, one JSON per profile. Finished trainings and evaluations are found
on disk and never recomputed, so a restarted sweep only does what is missing. Cells run on a local process pool
or as Ray tasks on a cluster; either way they write into the same folder layout:

```
OUT/
  sweep.yaml                          the sweep's spec (a restart with another spec is refused)
  cells/<train>-seed<k>/run/          the training run folder
  cells/<train>-seed<k>/eval-<p>.json evaluation under profile p
  sweep.csv                           one row per (train profile, seed, eval profile)
  heatmap.png                         success and collision rate, train profile x eval profile, mean over seeds
                                      (and each seed's), the diagonal outlined
  summary.md                          per train profile: the diagonal, clean evaluation, and what training
                                      under noise cost on clean evaluation
```
"""

from __future__ import annotations

import csv
import json
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import yaml

from clutter_gym.training.config import EVAL_SEED, TrainConfig, config_for, deep_merge
from clutter_gym.util.atomic import atomic_path, write_text_atomically
from clutter_gym.util.checks import short_repr
from clutter_gym.util.safe_yaml import read_yaml

MIX = "+"  # joins the profiles of a mixed train profile, as in "none+nominal+low-cost"
#: puts a profile under a dynamics model (clutter_gym.dynamics), as in "none@reduced": the sim-to-sim gap in the
#: sweep's own terms (train under the reduced model, evaluate under full physics, or the reverse)
UNDER = "@"


def split_profile(name: str) -> tuple[str, str | None]:
    """(the noise part, the dynamics model or None) of a profile name such as ``"nominal@reduced"``."""
    noise, _, dynamics = name.partition(UNDER)
    return noise, dynamics or None


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep trains and evaluates.

    Attributes:
        env_id: env to train on.
        train_noise: profiles to train under; ``"a+b"`` trains a share of the envs under each of a and b;
            ``"a@reduced"`` trains under the env's reduced dynamics (its validations stay under the run's own).
        eval_noise: profiles to evaluate every run under; ``"a@reduced"`` evaluates under the reduced dynamics.
        seeds: training seeds 0..seeds-1 per train profile.
        timesteps: env steps per training run (None: the env's ppo.yml value).
        episodes: evaluation episodes per (run, eval profile); episode i uses seed 1,000,000 + i.
        n_envs: envs per training run (None: the env's ppo.yml value).
        settings: config overrides for every run (a user's hyperparameter file and ``--env-kwargs``), resolved
            into plain data so that they travel to Ray workers.
    """

    env_id: str
    train_noise: tuple[str, ...]
    eval_noise: tuple[str, ...]
    seeds: int
    timesteps: int | None
    episodes: int
    n_envs: int | None = None
    settings: dict[str, Any] = field(default_factory=dict)

    def cells(self) -> list[tuple[str, int]]:
        return [(noise, seed) for noise in self.train_noise for seed in range(self.seeds)]

    def cell_config(self, train_noise: str, seed: int) -> TrainConfig:
        """A cell's training config. A train profile ``"a+b+..."`` is a mix: a share of the training envs under
        each profile (``train_env_mix``), validations under the first; ``"...@model"`` trains every env under that
        dynamics model (``train_env_mix``), validations under the run's own."""
        noise, dynamics = split_profile(train_noise)
        profiles = noise.split(MIX)
        overrides: dict[str, Any] = {"seed": seed, "noise": profiles[0], "final_eval_episodes": 0}
        mix: dict[str, list[str]] = {"noise": profiles} if len(profiles) > 1 else {}
        if dynamics is not None:
            mix["dynamics"] = [dynamics]
        if mix:
            overrides["train_env_mix"] = mix
        for key in ("timesteps", "n_envs"):
            if getattr(self, key) is not None:
                overrides[key] = getattr(self, key)
        return config_for(self.env_id, deep_merge(self.settings, overrides))

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["train_noise"], data["eval_noise"] = list(self.train_noise), list(self.eval_noise)
        return data


def cell_dir(out: Path, train_noise: str, seed: int) -> Path:
    return out / "cells" / f"{train_noise}-seed{seed}"


def cell_done(spec: SweepSpec, out: Path, train_noise: str, seed: int) -> bool:
    folder = cell_dir(out, train_noise, seed)
    return all((folder / f"eval-{p}.json").is_file() for p in spec.eval_noise)


def run_cell(spec_data: dict[str, Any], out: str, train_noise: str, seed: int, env_workers: int | None = None) -> str:
    """Train (or resume, or skip if finished) one cell's run, then each missing evaluation. Returns the cell name.

    ``env_workers`` sets the processes that step the cell's training envs (None: the config's), which changes the
    speed of training and nothing else: a Ray cell steps its envs over exactly the CPUs it reserved.
    """
    from clutter_gym.training.evaluate import evaluate
    from clutter_gym.training.run_dir import RunDir
    from clutter_gym.training.train import start, train

    spec = SweepSpec(**{**spec_data, "train_noise": tuple(spec_data["train_noise"]),
                        "eval_noise": tuple(spec_data["eval_noise"])})
    folder = cell_dir(Path(out), train_noise, seed)
    run = RunDir(folder / "run")
    if not run.config_file.is_file():
        start(spec.cell_config(train_noise, seed), run.root)
    if not run.is_finished():
        train(run, progress=False, env_workers=env_workers)
    for profile in spec.eval_noise:
        target = folder / f"eval-{profile}.json"
        if not target.is_file():
            noise, dynamics = split_profile(profile)
            summary = evaluate(run.root, noise=noise, episodes=spec.episodes, seed=EVAL_SEED,
                               env_overrides=None if dynamics is None else {"dynamics": dynamics})
            summary.pop("per_episode")
            write_text_atomically(target, json.dumps(summary, indent=2))
    return folder.name


def run_sweep(spec: SweepSpec, out: Path, workers: int | None = None, ray_address: str | None = None,
              cpus_per_cell: int | None = None) -> dict[str, Any]:
    """Run every unfinished cell (process pool, or Ray tasks when ``ray_address`` is given), then write CSV and plot.

    ``ray_address`` is passed to ``ray.init``: ``"auto"``, ``"HEAD:6379"`` or ``"ray://HEAD:10001"`` for a running
    cluster, or ``"local"`` to start a throwaway local Ray instance. A Ray cell reserves ``cpus_per_cell`` CPUs of
    one node (None: the config's ``env_workers``, or 1 when that is 0, "one per core", which means nothing before a
    node is chosen) and steps its training envs over that many processes.

    Returns:
        ``cells_run``, ``cells_skipped``, ``csv``, ``heatmap``, ``rows`` and, for Ray, ``nodes``: the id of the
        node that ran each cell.

    Raises:
        ValueError: a cell asks for more CPUs than any node of the Ray cluster has.
    """
    check_spec(spec, out)
    spec_file = out / "sweep.yaml"
    if not spec_file.is_file():
        write_text_atomically(spec_file, yaml.safe_dump(spec.to_dict(), sort_keys=False))
    todo = [cell for cell in spec.cells() if not cell_done(spec, out, *cell)]
    nodes: dict[str, str] = {}
    if todo and ray_address is not None:
        cpus = cpus_per_cell or spec.cell_config(*todo[0]).env_workers or 1
        nodes = _run_on_ray(spec, out, todo, ray_address, cpus)
    elif todo:
        _run_on_pool(spec, out, todo, workers)
    rows = collect_rows(spec, out)
    csv_path = write_csv(rows, out / "sweep.csv")
    heatmap = write_heatmap(rows, spec, out / "heatmap.png")
    summary = out / "summary.md"
    write_text_atomically(summary, summary_table(rows, spec))
    result = {"cells_run": len(todo), "cells_skipped": len(spec.cells()) - len(todo), "csv": str(csv_path),
              "heatmap": str(heatmap), "summary": str(summary), "rows": rows}
    return {**result, "nodes": nodes} if ray_address is not None else result


def check_spec(spec: SweepSpec, out: Path) -> None:
    """Refuse settings that no cell could train with, and a folder that holds a sweep with another spec.

    Raises:
        ValueError: a bad setting (named), or a different sweep in ``out``.
    """
    from clutter_gym.training.train import check_env_builds

    for noise in spec.train_noise:
        check_env_builds(spec.cell_config(noise, 0))
    spec_file = out / "sweep.yaml"
    if spec_file.is_file():
        saved = read_yaml(spec_file)
        saved = {"settings": {}, **saved} if isinstance(saved, dict) else saved  # sweeps older than settings had none
        if saved != spec.to_dict():
            raise ValueError(f"{out} holds a sweep with another spec ({short_repr(saved)}); use a new --out")


def _run_on_pool(spec: SweepSpec, out: Path, todo: list[tuple[str, int]], workers: int | None) -> None:
    workers = min(workers or os.cpu_count() or 1, len(todo))
    # forkserver, not fork: a forked worker would inherit this process's forkserver (if a vector env started one) as a
    # process that is not its child, and its cell's own worker processes could not start
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("forkserver")) as pool:
        futures = [pool.submit(run_cell, spec.to_dict(), str(out), noise, seed) for noise, seed in todo]
        for future in as_completed(futures):
            print(f"  cell {future.result()} done", flush=True)


def _run_on_ray(spec: SweepSpec, out: Path, todo: list[tuple[str, int]], address: str, cpus: int) -> dict[str, str]:
    """Each cell as a Ray task of ``cpus`` CPUs, spread over the nodes; returns the node id of each cell."""
    try:
        import ray
    except ImportError as exc:
        raise RuntimeError("--ray-address needs Ray: pip install 'clutter-gym[ray]'") from exc
    started_here = not ray.is_initialized()
    if started_here:
        ray.init(address=None if address == "local" else address, include_dashboard=False, log_to_driver=False)
    try:
        largest = max((node["Resources"].get("CPU", 0.0) for node in ray.nodes() if node["Alive"]), default=0.0)
        if cpus > largest:  # Ray would keep the task pending for a node that never comes, silently
            raise ValueError(f"each cell asks Ray for {cpus} CPUs (--cpus-per-cell, default: env_workers) and the "
                             f"largest node of the cluster at {address!r} has {largest:g}; pass --cpus-per-cell "
                             f"{max(int(largest), 1)} or add bigger nodes")
        task = ray.remote(num_cpus=cpus, scheduling_strategy="SPREAD")(_ray_cell)
        pending = [task.remote(spec.to_dict(), str(out.resolve()), noise, seed, cpus) for noise, seed in todo]
        nodes = {}
        while pending:
            finished, pending = ray.wait(pending)
            cell, node = ray.get(finished[0])
            nodes[cell] = node
            print(f"  cell {cell} done (ray node {node[:12]})", flush=True)
        return nodes
    finally:
        if started_here:
            ray.shutdown()


def _ray_cell(*args: Any) -> tuple[str, str]:
    """:func:`run_cell` in a Ray task; returns the cell's name and the id of the node it ran on."""
    import ray

    return run_cell(*args), ray.get_runtime_context().get_node_id()


def collect_rows(spec: SweepSpec, out: Path) -> list[dict[str, Any]]:
    """One row per (train profile, seed, eval profile): the episode count, then each of evaluate's ``METRICS`` with
    its 95% interval's ends, in that order (sweep.csv's columns)."""
    from clutter_gym.training.evaluate import METRICS

    rows = []
    for train_noise, seed in spec.cells():
        for profile in spec.eval_noise:
            summary = json.loads((cell_dir(out, train_noise, seed) / f"eval-{profile}.json").read_text())
            row: dict[str, Any] = {"train_noise": train_noise, "seed": seed, "eval_noise": profile,
                                   "episodes": summary["episodes"]}
            for name in METRICS:
                metric = summary["metrics"][name]
                row[name] = metric["value"]
                row[f"{name}_ci_low"], row[f"{name}_ci_high"] = metric["ci95"]
            rows.append(row)
    return rows


def write_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    with atomic_path(path) as tmp, tmp.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def per_seed(rows: list[dict[str, Any]], metric: str, train_noise: str, eval_noise: str) -> list[float]:
    """``metric`` of each seed trained under ``train_noise`` and evaluated under ``eval_noise``, in seed order."""
    return [r[metric] for r in sorted(rows, key=lambda r: r["seed"])
            if r["train_noise"] == train_noise and r["eval_noise"] == eval_noise]


def summary_table(rows: list[dict[str, Any]], spec: SweepSpec) -> str:
    """A markdown table, one row per train profile: success / collision rate evaluated under the same profile (the
    diagonal) and clean (``none``), and the clean success it costs against training clean, each the mean over
    seeds with every seed's value in brackets. Without ``none`` among both profiles' lists, the diagonal only."""
    import numpy as np

    def rates(train: str, evaluated: str) -> str:
        success, collision = (per_seed(rows, m, train, evaluated) for m in ("success_rate", "collision_rate"))
        seeds = f" ({', '.join(f'{s:.0%} / {c:.0%}' for s, c in zip(success, collision))})" if len(success) > 1 else ""
        return f"{np.mean(success):.0%} / {np.mean(collision):.0%}{seeds}"

    clean = "none" in spec.eval_noise and "none" in spec.train_noise
    header = ["trained under", "evaluated under the same profile"]
    if clean:
        header += ["evaluated clean (`none`)", "clean success lost to training under noise"]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for train in spec.train_noise:
        cells = [f"`{train}`", rates(train, train) if train in spec.eval_noise else "-"]
        if clean:
            lost = np.subtract(per_seed(rows, "success_rate", "none", "none"),
                               per_seed(rows, "success_rate", train, "none"))
            spread = f" ({', '.join(f'{100 * v:+.0f}' for v in lost)})" if len(lost) > 1 else ""
            cells += [rates(train, "none"), f"{100 * np.mean(lost):+.0f} points{spread}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + (f"\n\n{spec.env_id}, success / collision episodes, {spec.episodes} episodes per seed "
                               f"and cell, {spec.seeds} seed(s); sweep.csv has each seed's 95% intervals.\n")


def write_heatmap(rows: list[dict[str, Any]], spec: SweepSpec, path: Path) -> Path:
    """Two panels (success rate, collision rate): rows = train profile, columns = eval profile, the mean over seeds
    (each seed's value under it), the cells trained and evaluated under the same profile outlined."""
    import numpy as np

    from clutter_gym.training.figures import plt, save_figure

    fig, axes = plt.subplots(1, 2, figsize=(4 + 1.6 * len(spec.eval_noise), 1.5 + 0.8 * len(spec.train_noise)))
    for ax, metric, cmap in zip(axes, ("success_rate", "collision_rate"), ("viridis", "magma_r")):
        grid = [[per_seed(rows, metric, t, e) for e in spec.eval_noise] for t in spec.train_noise]
        ax.imshow(np.array([[np.mean(values) for values in line] for line in grid]), vmin=0.0, vmax=1.0, cmap=cmap)
        for i, line in enumerate(grid):
            for j, values in enumerate(line):
                text = f"{np.mean(values):.0%}" + ("\n" + " ".join(f"{v:.0%}" for v in values) if len(values) > 1
                                                   else "")
                ax.text(j, i, text, ha="center", va="center", fontsize=8,
                        bbox={"facecolor": "white", "alpha": 0.7, "lw": 0})
                if spec.train_noise[i] == spec.eval_noise[j]:
                    ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, edgecolor="red", lw=2))
        ax.set_xticks(range(len(spec.eval_noise)), spec.eval_noise)
        ax.set_yticks(range(len(spec.train_noise)), spec.train_noise)
        ax.set_xlabel("evaluated under")
        ax.set_ylabel("trained under")
        ax.set_title(metric.replace("_", " "))
    fig.suptitle(f"{spec.env_id}: {spec.seeds} seed(s), {spec.episodes} episodes per cell")
    return save_figure(fig, path)
