"""Tiny training runs: the run folder, resume, crash-safe checkpoints, evaluation schema and episode statistics."""

from __future__ import annotations

import json
import math

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym.cli import main
from clutter_gym.training import load
from clutter_gym.training.config import config_for
from clutter_gym.training.episode_stats import EPISODE_KEYS, EpisodeStats
from clutter_gym.training.evaluate import METRICS, evaluate
from clutter_gym.training.normalizer import NORMALIZER_FILE
from clutter_gym.training.run_dir import MODEL_FILE, RunDir
from clutter_gym.training.train import start, train

# Small enough to run in seconds; short episodes so that some finish inside the budget.
TINY = {"timesteps": 256, "n_envs": 1, "checkpoint_every": 128, "final_eval_episodes": 2,
        "env_kwargs": {"obstacle_density": 0.05}, "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 2}}


def tiny_run(tmp_path, **overrides):
    config = config_for("ClutterNav-v1", {**TINY, **overrides})
    return start(config, tmp_path / "run")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    run = tiny_run(tmp_path_factory.mktemp("trained"))
    summary = train(run, progress=False)
    return run, summary


def test_a_tiny_run_leaves_a_complete_loadable_run_folder(trained):
    run, summary = trained
    assert run.read_config().timesteps == 256
    assert (run.model_dir / MODEL_FILE).is_file() and (run.model_dir / NORMALIZER_FILE).is_file()
    assert [step for step, _ in run.checkpoints()] == [128, 256]  # every checkpoint_every steps
    assert any(run.tb_dir.glob("events.out.tfevents.*"))
    assert json.loads(run.eval_file.read_text())["metrics"].keys() == set(METRICS)
    agent = load(run.root)
    env = agent.make_env()
    obs, _ = env.reset(seed=0)
    action, state = agent.predict(obs)
    env.close()
    assert action.shape == (2,) and np.all(np.isfinite(action)) and state is None
    assert agent.step == 256 and agent.folder == run.model_dir
    assert summary["model_step"] == 256


def test_resume_continues_the_step_count_from_the_newest_checkpoint(tmp_path):
    run = tiny_run(tmp_path, final_eval_episodes=0)
    train(run, progress=False)
    # Pretend the run was killed after its second checkpoint: drop the final model and the last checkpoint.
    import shutil

    shutil.rmtree(run.model_dir)
    shutil.rmtree(run.latest_checkpoint()[1])
    assert run.latest_checkpoint()[0] == 128
    train(run, progress=False, timesteps=384)
    assert load(run.root).step == 384
    assert run.read_config().timesteps == 384
    steps = [row["timestep"] for row in run.read_episodes()]
    assert steps == sorted(steps)


def test_an_interrupted_checkpoint_write_leaves_the_previous_checkpoint_intact(trained, tmp_path):
    run, _ = trained
    before = run.latest_checkpoint()

    class DiesMidWrite:
        def save(self, path):
            with open(path, "wb") as f:
                f.write(b"PK\x03\x04 half a zip")
            raise KeyboardInterrupt("killed while writing")

    with pytest.raises(KeyboardInterrupt):
        run.save_checkpoint(DiesMidWrite(), None, step=10_000, keep=3)
    assert run.latest_checkpoint() == before
    assert not list(run.checkpoints_dir.glob(".step_*")), "the temporary folder must be removed"
    assert load(run.root, step=before[0]).folder == before[1]  # still loads


def test_a_new_run_refuses_a_folder_that_already_holds_one(trained):
    run, _ = trained
    with pytest.raises(FileExistsError, match="--resume"):
        start(run.read_config(), run.root)


def test_eval_json_schema_and_intervals(trained, tmp_path, capsys):
    run, _ = trained
    video = tmp_path / "episode.gif"
    assert main(["eval", str(run.root), "--noise", "nominal", "--episodes", "3", "--seed", "5", "--json",
                 "--video", str(video)]) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out.strip().splitlines()[-1])
    assert "evaluation: 100%" in captured.err and "3/3" in captured.err  # the progress bar, on stderr
    assert {"run", "env_id", "train_noise", "eval_noise", "seed", "episodes", "model_step", "metrics", "video",
            "per_episode"} <= summary.keys()
    assert summary["eval_noise"] == "nominal" and summary["episodes"] == 3 and len(summary["per_episode"]) == 3
    for name in METRICS:
        value, (low, high) = summary["metrics"][name]["value"], summary["metrics"][name]["ci95"]
        assert low <= value <= high
    assert 0.0 <= summary["metrics"]["success_rate"]["ci95"][0] <= summary["metrics"]["success_rate"]["ci95"][1] <= 1.0
    assert video.stat().st_size > 1000


def test_evaluation_is_reproducible_and_pairs_layouts_across_profiles(trained):
    run, _ = trained
    a = evaluate(run.root, noise="none", episodes=2, seed=11)
    b = evaluate(run.root, noise="none", episodes=2, seed=11)
    assert a["per_episode"] == b["per_episode"]


def test_evaluate_rejects_bad_arguments(trained):
    run, _ = trained
    with pytest.raises(ValueError, match="noise"):
        evaluate(run.root, noise="loud", episodes=2, seed=0)
    with pytest.raises(ValueError, match="episodes"):
        evaluate(run.root, noise="none", episodes=0, seed=0)
    with pytest.raises(FileNotFoundError, match="config.yaml"):
        evaluate(run.root / "nothing", noise="none", episodes=1, seed=0)


def test_episode_stats_sum_the_step_infos():
    env = EpisodeStats(gym.make("ClutterNav-v1", max_episode_steps=30))
    obs, info = env.reset(seed=3)
    total, costs, clearances, terms = 0.0, 0.0, [info["min_clearance"]], {}
    while True:
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.3], dtype=np.float32))
        total += reward
        costs += info["cost"]
        clearances.append(info["min_clearance"])
        for k, v in info["reward_terms"].items():
            terms[k] = terms.get(k, 0.0) + v
        if terminated or truncated:
            break
    env.close()
    stats = info["episode_stats"]
    assert set(EPISODE_KEYS) <= stats.keys()
    assert stats["return"] == pytest.approx(total) and stats["cost"] == pytest.approx(costs)
    assert stats["collision"] == float(costs > 0) and stats["min_clearance"] == pytest.approx(min(clearances))
    assert stats["length"] == 30.0
    assert all(stats[f"term_{k}"] == pytest.approx(v) for k, v in terms.items())
    assert math.isclose(sum(stats[f"term_{k}"] for k in terms), total, rel_tol=1e-9, abs_tol=1e-9)


def test_worker_vector_env_trains_with_two_workers(tmp_path):
    run = tiny_run(tmp_path, n_envs=3, env_workers=2, timesteps=192, final_eval_episodes=0)
    train(run, progress=False)
    assert RunDir(run.root).is_finished()


def test_evaluation_takes_env_overrides_and_records_them(trained, capsys):
    run, _ = trained
    overrides = {"obstacle_density": 0.2, "noise": {"lidar": {"range_sigma": 0.05}}}
    summary = evaluate(run.root, noise="nominal", episodes=1, seed=3, env_overrides=overrides)
    assert summary["env_overrides"] == overrides and summary["eval_noise"] == "nominal"
    with pytest.raises(SystemExit) as exit_info:
        main(["eval", str(run.root), "--episodes", "1", "--env-kwargs", "n_rays=8"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "observations of shape" in err and len(err.strip().splitlines()) == 1


def test_validations_keep_the_best_policy_which_load_and_evaluation_then_use(tmp_path):
    run = tiny_run(tmp_path, validate_every=128, validate_episodes=2,
                   env_kwargs={"obstacle_density": 0.05, "max_episode_steps": 30})
    summary = train(run, progress=False)
    rows = run.read_validations()
    assert [r["step"] for r in rows] == [128, 256]
    assert rows[0]["best"] == 1.0  # the first validation is always the best so far
    best = max(rows, key=lambda r: (r["success"] - r["collision"], r["step"]))  # ties: the later policy
    assert sum(r["best"] for r in rows) >= 1 and all(0.0 <= r["success"] <= 1.0 for r in rows)
    assert (run.best_dir / MODEL_FILE).is_file() and (run.best_dir / NORMALIZER_FILE).is_file()
    agent = load(run.root)
    assert agent.folder == run.best_dir and agent.step == best["step"]
    assert summary["model"] == "best" and summary["model_step"] == best["step"]


def test_the_same_policy_validates_alike_on_its_fixed_held_out_layouts(tmp_path):
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import configure

    from clutter_gym.training.callbacks import BestPolicyKeeper

    run = tiny_run(tmp_path, validate_every=64, validate_episodes=2,
                   env_kwargs={"obstacle_density": 0.05, "max_episode_steps": 20})
    config = run.read_config()
    model = PPO("MultiInputPolicy", gym.make("ClutterNav-v1", **config.make_kwargs()), seed=0, device="cpu",
                n_steps=64, batch_size=32)
    model.set_logger(configure(None, []))
    keepers = [BestPolicyKeeper(run, config) for _ in range(2)]
    results = []
    for keeper in keepers:
        keeper.init_callback(model)
        keeper._on_training_start()
        results.append(keeper.validate())
        keeper._on_training_end()
    assert results[0] == results[1] and results[1]["best"] == 1.0  # a tie keeps the later policy


def test_the_main_job_reports_its_verdict_and_shows_two_episodes_side_by_side(tmp_path):
    import imageio.v2 as imageio

    from clutter_gym.training.report import main_job, prepare_run

    settings = {"n_envs": 1, "checkpoint_every": 128, "validate_every": 128, "validate_episodes": 1,
                "env_kwargs": {"max_episode_steps": 25}, "ppo": {"n_steps": 64, "batch_size": 32, "n_epochs": 1}}
    run = prepare_run("ClutterNav-v1", tmp_path, timesteps=128, seed=0, settings=settings)
    report = main_job(run, tmp_path, timesteps=128, episodes=2, progress=False).read_text()
    assert "**Map-based agent.**" in report  # the shipped ClutterNav settings tell the policy the subgoal
    assert "**Behind a collision monitor**" in report and "next 0.3 s of driving" in report
    assert "after 0.5 s held still it turns the base" in report
    assert "Target on clean sensors" in report and "**missed**" in report  # 128 steps of training cannot meet it
    assert "Evaluated policy: `best`" in report
    assert "min evaluating, on " in report and " cores, load average " in report  # what the times ran on
    frames = imageio.mimread(tmp_path / "episode.gif")
    height, width = frames[0].shape[:2]
    assert height >= 360 and width >= 2 * 360  # two readable panels
    assert (tmp_path / "learning_curve.png").is_file()


def test_episode_pictures_draw_the_planner_path_and_every_step(tmp_path):
    from clutter_gym.training.baselines import PotentialFieldNavigator
    from clutter_gym.training.episode_view import draw_frame, record_episode

    env = gym.make("ClutterNav-v1", subgoal_lookahead=0.5, max_episode_steps=30)
    navigator = PotentialFieldNavigator.for_env(env, goal_key="subgoal")
    trace = record_episode(env, lambda obs, state: (navigator(obs), None), seed=3, title="scripted")
    env.close()
    assert len(trace.poses) == len(trace.captions) == len(trace.ranges) == 31  # the reset and 30 steps
    assert trace.path[0] == pytest.approx(trace.poses[0][:2]) and trace.path[-1] == pytest.approx(trace.scene.goal)
    assert "step 30" in trace.captions[-1] and "progress" in trace.captions[-1]
    first, last = draw_frame([trace], 0), draw_frame([trace], 30)
    assert first.shape == last.shape and first.shape[0] >= 360 and not np.array_equal(first, last)


def test_episode_captions_say_what_the_collision_monitor_did():
    from clutter_gym.training.episode_view import _monitor_text

    assert _monitor_text({"safety_scale": 1.0, "safety_recovery": False}) == ""
    assert _monitor_text({}) == ""  # no monitor
    assert _monitor_text({"safety_scale": 0.25, "safety_recovery": False}) == " | monitor: speed x0.25"
    assert _monitor_text({"safety_scale": 0.0, "safety_recovery": True}) == " | monitor: recovery spin"


def test_the_verdict_holds_each_env_to_its_own_target():
    from clutter_gym import ENV_IDS
    from clutter_gym.training.report import TARGETS, _verdict

    assert set(TARGETS) == set(ENV_IDS)
    metrics = {"success_rate": {"value": 0.85}, "collision_rate": {"value": 0.08}}
    assert "**met**" in _verdict("ClutterFly-v1", metrics, 600.0) and "at least 80% success" in _verdict(
        "ClutterFly-v1", metrics, 600.0)
    assert "**missed**" in _verdict("ClutterNav-v1", metrics, 600.0)
    assert "**missed**" in _verdict("ClutterFly-v1", metrics, 16 * 60.0)
