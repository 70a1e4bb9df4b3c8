"""The main job: train PPO with the defaults, evaluate clean and under the nominal profile, write a short report.

``OUT/report.md`` (metrics with 95% intervals, the config, timings), ``OUT/learning_curve.png`` (success and
collision rate over training, and the validations), ``OUT/episode.gif`` (for ClutterNav a successful and a failed
evaluation episode side by side, top-down; the env's own render for other envs), ``OUT/eval-<p>.json``
and the run folder ``OUT/run``. Rerunning resumes an unfinished run and reuses a finished one.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from clutter_gym.robots.safety import SafetyConfig
from clutter_gym.training.config import EVAL_SEED, config_for, deep_merge
from clutter_gym.training.evaluate import evaluate
from clutter_gym.training.run_dir import RunDir
from clutter_gym.training.train import start, train
from clutter_gym.util.atomic import write_text_atomically
from clutter_gym.util.machine import machine_state

PROFILES = ("none", "nominal")
WINDOW = 100


def prepare_run(env_id: str, out: Path, timesteps: int | None, seed: int, settings: dict | None = None) -> RunDir:
    """``OUT/run``: started with the resolved settings, or the run already there if it has those settings.

    Raises:
        ValueError: ``OUT/run`` holds a run with other settings (another budget is fine: the run continues to
            it), or a setting is bad (named).
    """
    run = RunDir(out / "run")
    overrides = deep_merge(settings or {}, {"seed": seed, "final_eval_episodes": 0})
    if timesteps is not None:
        overrides["timesteps"] = timesteps
    config = config_for(env_id, overrides)
    if not run.config_file.is_file():
        return start(config, run.root)
    saved = run.read_config()
    differ = _differences(saved.to_dict(), config.to_dict(), ignore={"timesteps"})
    if differ:
        raise ValueError(f"{run.root} holds a run with other settings ({', '.join(differ)}); pass another --out, "
                         "or the options it was started with")
    return run


def _differences(saved: dict, wanted: dict, ignore: set[str], prefix: str = "") -> list[str]:
    """The settings (dotted names, both values) that differ between two config dicts, less those in ``ignore``."""
    names = []
    for key in sorted(set(saved) | set(wanted)):
        a, b = saved.get(key), wanted.get(key)
        if prefix + key in ignore or a == b:
            continue
        if isinstance(a, dict) and isinstance(b, dict):
            names += _differences(a, b, ignore, f"{prefix}{key}.")
        else:
            names.append(f"{prefix}{key}: {a!r} in the run, {b!r} asked")
    return names


def main_job(run: RunDir, out: Path, timesteps: int | None, episodes: int, progress: bool = True) -> Path:
    """Train (or resume / reuse) ``run``, evaluate it under each of PROFILES, write the report; returns its path."""
    machine = machine_state()
    t0 = time.perf_counter()
    if not run.is_finished() or (timesteps is not None and timesteps != run.read_config().timesteps):
        train(run, progress=progress, timesteps=timesteps)
    train_s = time.perf_counter() - t0
    summaries = {}
    t0 = time.perf_counter()
    navigation = run.read_config().env_id == "ClutterNav-v1"
    for profile in PROFILES:
        video = out / "episode.gif" if profile == "none" and not navigation else None
        summary = evaluate(run.root, noise=profile, episodes=episodes, seed=EVAL_SEED, video=video, progress=progress)
        write_text_atomically(out / f"eval-{profile}.json", json.dumps(summary, indent=2))
        summaries[profile] = summary
    eval_s = time.perf_counter() - t0
    if navigation:
        write_episode_pair(run, summaries["none"], out / "episode.gif", progress=progress)
    curve = plot_learning_curve(run, out / "learning_curve.png")
    report = out / "report.md"
    write_text_atomically(report, render_report(run, summaries, curve, train_s, eval_s, machine))
    return report


def write_episode_pair(run: RunDir, summary: dict, path: Path, progress: bool = False) -> Path:
    """The first successful and the first failed episode of an evaluation, replayed side by side (top-down, with
    trail, LIDAR beams, planner path and reward terms); two successes or two failures if there is no other kind.
    ``progress`` shows a bar of the frames drawn."""
    from clutter_gym.training.agent import load
    from clutter_gym.training.episode_view import record_episode, write_episodes_video

    rows = summary["per_episode"]
    wins = [i for i, r in enumerate(rows) if r["success"]]
    losses = [i for i, r in enumerate(rows) if not r["success"]]
    picks = (wins[:1] + losses[:1]) if wins and losses else (wins or losses)[:2]
    agent = load(run.root)
    env = agent.make_env(noise=summary["eval_noise"])
    try:
        traces = [record_episode(env, agent.predict, summary["seed"] + i,
                                 f"{'success' if rows[i]['success'] else 'failure'}, seed {summary['seed'] + i}")
                  for i in picks]
    finally:
        env.close()
    return write_episodes_video(path, traces, fps=env.metadata["render_fps"], progress=progress)


def rolling_rate(values: np.ndarray, window: int = WINDOW) -> np.ndarray:
    """Mean of each entry and the up to ``window - 1`` before it (the rate over the latest episodes)."""
    values = np.asarray(values, dtype=float)
    return (np.convolve(values, np.ones(window), "full")[: len(values)]
            / np.minimum(np.arange(1, len(values) + 1), window))


def plot_learning_curve(run: RunDir, path: Path) -> Path | None:
    """Success and collision rate over the last 100 training episodes, against env steps."""
    rows = run.read_episodes()
    if not rows:
        return None
    from clutter_gym.training.figures import plt, save_figure

    steps = np.array([r["timestep"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    validations = run.read_validations()
    for key, label in (("success", "success rate"), ("collision", "collision rate")):
        line, = ax.plot(steps, rolling_rate(np.array([r[key] for r in rows])), label=f"{label}, training")
        if validations:
            ax.plot([v["step"] for v in validations], [v[key] for v in validations], "o", color=line.get_color(),
                    label=f"{label}, validation")
    ax.set_xlabel("env steps")
    ax.set_ylabel(f"rate over the last {WINDOW} episodes")
    ax.set_ylim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend()
    config = run.read_config()
    ax.set_title(f"PPO on {config.env_id} (seed {config.seed}, training noise {config.noise!r})")
    return save_figure(fig, path)


#: Per env, the target on clean sensors: success rate at least, collision rate at most, wall time of training and
#: evaluation at most. ClutterNav-v1's is the main job's; ClutterFly-v1's is its own issue's.
TARGETS = {
    "ClutterNav-v1": {"success_rate": 0.90, "collision_rate": 0.05, "minutes": 15.0},
    "ClutterReach-v1": {"success_rate": 0.90, "collision_rate": 0.05, "minutes": 15.0},
    "ClutterFly-v1": {"success_rate": 0.80, "collision_rate": 0.10, "minutes": 15.0},
}


def _verdict(env_id: str, metrics: dict, seconds: float) -> str:
    target = TARGETS[env_id]
    success, collision = metrics["success_rate"]["value"], metrics["collision_rate"]["value"]
    met = success >= target["success_rate"] and collision <= target["collision_rate"]
    timed = seconds / 60 <= target["minutes"]
    return (f"Target on clean sensors, at least {target['success_rate']:.0%} success and at most "
            f"{target['collision_rate']:.0%} collision episodes within {target['minutes']:.0f} minutes: "
            f"**{'met' if met and timed else 'missed'}** ({success:.0%} success, {collision:.0%} collisions, "
            f"{seconds / 60:.1f} min of training and evaluation).")


#: Per map-based env with a subgoal pursuit: what else the policy sees, the lookahead's unit, the path, the pursuit
#: a residual policy acts on, and who carries the skill then.
_MAP_BASED = {
    "ClutterReach-v1": ("its joints, clearances and the target", "rad",
                        "on a joint-space path planned over the known layout", "a pursuit of that subgoal",
                        "the planner carries most of the skill; the baseline table has the pursuit alone"),
    "ClutterFly-v1": ("the flight controller's state and the goal", "m",
                      "on the shortest path through the known layout",
                      "a cascaded position controller flying to that subgoal",
                      "the planner and the controller carry most of the skill; the baseline table has them alone"),
}


#: The sensor-only base controller a residual policy adds its actions to, per env.
_MAPLESS_BASE = {
    "ClutterNav-v1": "a potential field over the same LIDAR and goal",
    "ClutterReach-v1": "a joint-space potential field over the same proximity readings and target",
    "ClutterFly-v1": "a position controller flying straight at the goal, which sees no obstacle",
}


def _observation_line(config) -> str:
    lookahead = config.env_kwargs.get("subgoal_lookahead", 0.0)
    if lookahead and config.env_id in _MAP_BASED:
        sees, unit, path, pursuit, skill = _MAP_BASED[config.env_id]
        line = (f"**Map-based agent.** Besides {sees}, the policy is told the subgoal: the point {lookahead} "
                f"{unit} ahead {path}.")
        if config.residual_gain:
            line += (f" Its actions are residuals on {pursuit} (`residual_gain` {config.residual_gain:g}): the env "
                     f"is driven by the pursuit plus the policy's correction, so {skill}.")
        line += " It does not solve the mapless task; train without `subgoal_lookahead` for that."
    elif lookahead:
        line = (f"**Map-based agent.** Besides the LIDAR and the goal, the policy is told the subgoal: the point "
                f"{lookahead} m ahead on the path a costmap planner finds over the known layout. It does not solve "
                "the mapless task; train without `subgoal_lookahead` for that.")
    else:
        sensed = ("its joint positions and velocities, each link's proximity reading and the target's position"
                  if config.env_id == "ClutterReach-v1" else
                  f"its sensors ({', '.join(config.env_kwargs.get('sensors', ['the env default']))}), its own "
                  "velocity and the goal's position relative to it")
        line = (f"**Sensor-only agent.** The policy reads only what the robot measures: {sensed}; no map, no "
                "planner, no subgoal.")
        if config.residual_gain:
            line += (f" Its actions are residuals on {_MAPLESS_BASE[config.env_id]} "
                     f"(`residual_gain` {config.residual_gain:g})"
                     + (", added to the velocity it commands." if config.residual_space == "velocity" else "."))
        if config.env_kwargs.get("reverse") is False:
            line += " The base drives forwards only (`reverse: false`)."
    horizon = config.env_kwargs.get("safety_horizon", 0.0)
    if horizon:
        margin = config.env_kwargs.get("safety_margin", SafetyConfig.margin)
        recovery = config.env_kwargs.get("safety_recovery", SafetyConfig.recovery)
        line += (f" **Behind a collision monitor** (`safety_horizon`): the base slows down whenever the LIDAR "
                 f"sees its next {horizon} s of driving come within {margin} m of an obstacle")
        if recovery:
            line += (f", and after {recovery} s held still it turns the base in place away from the nearest "
                     "obstacle (`safety_recovery`)")
        line += "; the figures below are the policy and the monitor together."
    return line


def render_report(run: RunDir, summaries: dict, curve: Path | None, train_s: float, eval_s: float,
                  machine: str) -> str:
    """report.md: the run, its times and the ``machine`` they were measured on (:func:`machine_state`), the
    evaluation table, the verdict, the learning curve and the episode GIF."""
    config = run.read_config()
    lines = [
        f"# PPO on {config.env_id}",
        "",
        f"PPO, {config.timesteps:,} env steps with {config.n_envs} envs, seed {config.seed}, training noise profile "
        f"{config.noise!r}; this invocation spent {train_s / 60:.1f} min training (0 when it reused a finished run) "
        f"and {eval_s / 60:.1f} min evaluating, on {machine}. Config: `{run.config_file}`.",
        "",
        _observation_line(config),
        "",
        "| metric | " + " | ".join(f"eval `{p}`" for p in summaries) + " |",
        "|---|" + "---|" * len(summaries),
    ]
    first = next(iter(summaries.values()))
    for name in first["metrics"]:
        cells = []
        for summary in summaries.values():
            metric = summary["metrics"][name]
            low, high = metric["ci95"]
            cells.append(f"{metric['value']:.3f} [{low:.3f}, {high:.3f}]")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += [
        "",
        f"{first['episodes']} episodes per profile, seeds {first['seed']}.., the same layouts under each profile; "
        "brackets are 95% intervals (Wilson for rates, Student t for means). A collision episode is one with any "
        f"contact. Evaluated policy: `{first['model']}` of the run, trained for {first['model_step']:,} steps"
        + (" (the best of the validations during training)." if first["model"] == "best" else "."),
        "",
    ]
    if "none" in summaries:
        lines += [_verdict(config.env_id, summaries["none"]["metrics"], run.training_time()["seconds"] + eval_s), ""]
    if curve is not None:
        lines += [f"![learning curve]({curve.name})", ""]
    lines += ["![evaluation episodes, clean sensors](episode.gif)", ""]
    if config.env_id == "ClutterNav-v1":
        from clutter_gym.training.episode_view import EVERY, SPEEDUP

        lines += [f"*Every {EVERY}th step of two evaluation episodes, at {SPEEDUP:g}x the real speed.*", ""]
    return "\n".join(lines)
