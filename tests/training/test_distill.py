"""The teacher -> student route: labels at the states the student visits, the aggregated data set, a student that
learns a known teacher, the privileged critic's split, and a loaded student that acts from its sensors alone."""

from __future__ import annotations

import re

import gymnasium as gym
import numpy as np
import pytest
import torch as th

from clutter_gym.training import load
from clutter_gym.training.baselines import PotentialFieldNavigator
from clutter_gym.training.config import config_for
from clutter_gym.training.distill import Dataset, disagreement, fit
from clutter_gym.training.distill_config import DistillSettings
from clutter_gym.training.privileged import PrivilegedCriticPolicy
from clutter_gym.training.teachers import Teacher, TeacherLabels, make_teacher
from clutter_gym.training.train import start, train
from clutter_gym.training.vec_env import student_keys

#: A small ClutterNav: a 3 m arena, few obstacles, a short LIDAR scan.
SMALL = {"arena_size": 3.0, "obstacle_density": 0.05, "n_rays": 16, "sensors": ["lidar"], "reverse": False,
         "observe_bearing": True, "max_episode_steps": 120, "subgoal_lookahead": 0.0}


def _student(**settings):
    return config_for("ClutterNav-v1", {
        "n_envs": 2, "env_workers": 1, "timesteps": 1, "validate_episodes": 2, "final_eval_episodes": 0,
        "teacher": {"name": "planner"}, "env_kwargs": SMALL, **settings})


def test_labels_are_the_teachers_action_at_the_state_the_policy_acted_in(make_env):
    env = make_env("ClutterNav-v1", **{**SMALL, "subgoal_lookahead": 0.5})
    field = PotentialFieldNavigator.for_env(env, goal_key="subgoal")
    labelled = TeacherLabels(env, make_teacher("ClutterNav-v1", "planner", env), teacher_share=0.0)
    obs, _ = labelled.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(30):
        expected = field(obs)  # the teacher at this state, before the step
        action = rng.uniform(-1, 1, 2).astype(np.float32)
        obs, _, terminated, truncated, info = labelled.step(action)
        np.testing.assert_array_equal(info["teacher_action"], expected)
        assert not info["teacher_drove"]
        if terminated or truncated:
            break


def test_a_teacher_driven_episode_takes_the_teachers_actions_and_the_draw_leaves_the_layouts_alone(make_env):
    kwargs = {**SMALL, "subgoal_lookahead": 0.5}
    driven = make_env("ClutterNav-v1", **kwargs)
    labelled = TeacherLabels(driven, make_teacher("ClutterNav-v1", "planner", driven), teacher_share=1.0)
    plain = make_env("ClutterNav-v1", **kwargs)
    field = PotentialFieldNavigator.for_env(plain, goal_key="subgoal")
    a, _ = labelled.reset(seed=5)
    b, _ = plain.reset(seed=5)
    for _ in range(20):
        a, *_, info = labelled.step(np.zeros(2, dtype=np.float32))  # ignored: the teacher drives
        b, *_ = plain.step(field(b))
        assert info["teacher_drove"]
        np.testing.assert_array_equal(a["lidar"], b["lidar"])


def test_the_data_set_aggregates_rounds_and_keeps_the_newest_samples():
    data = Dataset(max_samples=5)
    for start_value in (0, 3, 6):
        rows = np.arange(start_value, start_value + 3, dtype=np.float32)
        data.add({"x": rows[:, None]}, rows[:, None] * 10)
    obs, labels = data.arrays()
    np.testing.assert_array_equal(obs["x"][:, 0], [4, 5, 6, 7, 8])
    np.testing.assert_array_equal(labels[:, 0], [40, 50, 60, 70, 80])


def test_the_data_set_keeps_each_samples_weight_with_it():
    data = Dataset(max_samples=4)
    data.add({"x": np.zeros((3, 1))}, np.zeros((3, 1)), np.array([1.0, 2.0, 3.0]))
    data.add({"x": np.zeros((2, 1))}, np.zeros((2, 1)))  # unweighted: 1 each
    np.testing.assert_array_equal(data.weights(), [2.0, 3.0, 1.0, 1.0])


def test_disagreement_is_any_entry_further_than_the_threshold():
    labels = np.array([[0.0, 0.0], [0.0, 0.0], [0.5, -0.5]])
    student = np.array([[0.2, -0.2], [0.0, 0.3], [0.5, -0.5]])
    np.testing.assert_array_equal(disagreement(student, labels, 0.25), [False, True, False])


def test_the_fit_draws_samples_in_proportion_to_their_weights():
    """One observation labelled -1 as often as +1: unweighted, the student's likeliest bin is a coin toss between
    them; with the +1 samples weighing 9 times as much it must pick +1 (over three bins: -1, 0, +1)."""
    from gymnasium import spaces
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    class OneState(gym.Env):
        observation_space = spaces.Dict({"x": spaces.Box(-1, 1, (1,))})
        action_space = spaces.MultiDiscrete([3])

    model = PPO("MultiInputPolicy", make_vec_env(OneState, 1), seed=0, policy_kwargs={"net_arch": [8]})
    data = Dataset(max_samples=1000)
    labels = np.repeat([[-1.0], [1.0]], 100, axis=0)
    data.add({"x": np.zeros((200, 1))}, labels, np.where(labels[:, 0] > 0, 9.0, 1.0))
    settings = DistillSettings(epochs=20, batch_size=50, learning_rate=1e-2)
    fit(model, data, settings, th.optim.Adam(model.policy.parameters(), lr=settings.learning_rate), bins=3)
    x = {"x": th.zeros((1, 1))}
    assert model.policy.predict({"x": np.zeros((1, 1), np.float32)}, deterministic=True)[0][0, 0] == 2  # bin +1
    with th.no_grad():
        probs = model.policy.get_distribution(x).distribution[0].probs[0]
    assert 0.8 < probs[2] < 0.99  # the weighted share, 0.9, not the certainty a weight-free pick of +1 would give


def test_the_critic_reads_the_privileged_entries_and_the_actor_does_not(make_env):
    env = make_env("ClutterNav-v1", **{**SMALL, "subgoal_lookahead": 0.5})
    policy = PrivilegedCriticPolicy(env.observation_space, env.action_space, lambda _: 1e-3, critic_inputs=["subgoal"],
                                    net_arch=[16, 16])
    obs, _ = env.reset(seed=1)
    batch = {k: th.as_tensor(v[None]) for k, v in obs.items()}
    moved = {**batch, "subgoal": batch["subgoal"] + th.tensor([[0.3, 0.5, -0.4]])}
    with th.no_grad():
        assert th.equal(policy.get_distribution(batch).distribution.mean,
                        policy.get_distribution(moved).distribution.mean)  # the actor ignores the subgoal
        assert not th.equal(policy.predict_values(batch), policy.predict_values(moved))  # the critic reads it
    assert "subgoal" not in policy.pi_features_extractor.keys
    assert "subgoal" in policy.vf_features_extractor.keys
    action, _ = policy.predict({k: v for k, v in obs.items() if k != "subgoal"}, deterministic=True)
    assert action.shape == (2,)  # acting needs the student's entries only


def test_a_student_learns_a_teacher_it_can_see_to_95_percent_agreement(tmp_path, monkeypatch):
    """The planner teacher reads a subgoal the student cannot see, so agreement is bounded by what the map adds;
    a teacher on the student's own observation is realisable, and DAgger must then match it on the states the
    student itself visits (held-out layouts): agreement is every action entry within 0.1 of the teacher's. One
    worker, so the patched teacher is the one used."""
    monkeypatch.setattr("clutter_gym.training.teachers.make_teacher", GoalField)
    config = _student(timesteps=1, distill={"rounds": 5, "round_steps": 1200, "warmup_steps": 200, "epochs": 80},
                      ppo={"net_arch": [64, 64]})
    run = start(config, tmp_path / "run")
    train(run, progress=False)
    agent = load(run.root)
    env = agent.make_env()
    field = PotentialFieldNavigator(None, 1.0, forward_only=True)
    agreed = total = 0
    for seed in range(4):
        obs, _ = env.reset(seed=100 + seed)
        state, done = None, False
        while not done:
            action, state = agent.predict(obs, state)
            agreed += bool(np.all(np.abs(action - field(obs)) < 0.1))
            total += 1
            obs, _, terminated, truncated, _ = env.step(action)
            done = terminated or truncated
    env.close()
    assert agreed / total >= 0.95
    rows = run.read_distill_rows()
    assert [r["samples"] for r in rows] == [1200, 2400, 3600, 4800, 6000]  # aggregated: every round's samples kept
    assert rows[0]["teacher_share"] == 1.0 and rows[1]["teacher_share"] == 0.0


class GoalField(Teacher):
    """The potential field's goal seeking alone (no LIDAR): a scripted teacher that reads only the student's goal
    entry, so a student can match it exactly."""

    def __init__(self, env_id, name, env, space="action"):
        self.field = PotentialFieldNavigator(None, 1.0, forward_only=True)

    def __call__(self, obs, info):
        return self.field(obs)


def test_a_loaded_student_acts_from_an_env_whose_map_based_parts_are_switched_off(tmp_path, monkeypatch):
    config = _student(timesteps=2000, critic_inputs=["subgoal"],
                      distill={"rounds": 1, "round_steps": 400, "warmup_steps": 100, "bc_weight": 1.0})
    assert "subgoal" not in student_keys(config)
    run = start(config, tmp_path / "run")
    train(run, progress=False)
    assert (run.root / "distill.csv").is_file()

    def no_map(*args, **kwargs):
        raise AssertionError("a student asked for the planned path")

    monkeypatch.setattr("clutter_gym.worlds.floor.path.PathDistance.waypoint", no_map)
    monkeypatch.setattr("clutter_gym.worlds.floor.path.PathDistance.path", no_map)
    agent = load(run.root)
    env = agent.make_env()
    assert "subgoal" not in env.observation_space.spaces
    obs, _ = env.reset(seed=0)
    state = None
    for _ in range(20):
        action, state = agent.predict(obs, state)
        obs, *_ = env.step(action)
    env.close()


def test_a_teacher_the_env_does_not_have_is_refused_by_name():
    with pytest.raises(ValueError, match=r"teacher.name must be one of \['committed', 'in-range', 'planner', "
                                         r"'seen-map'\]"):
        config_for("ClutterNav-v1", {"teacher": {"name": "oracle"}})
    with pytest.raises(ValueError, match="env_kwargs.subgoal_lookahead must be 0 for a student"):
        config_for("ClutterNav-v1", {"teacher": {"name": "planner"}})  # the main job's block has a subgoal
    with pytest.raises(ValueError, match="critic_inputs needs a teacher"):
        config_for("ClutterNav-v1", {"critic_inputs": ["subgoal"]})
    with pytest.raises(ValueError, match="distill.rounds must be an integer in"):
        config_for("ClutterNav-v1", {"teacher": {"name": "planner"}, "distill": {"rounds": 0}})


def test_a_waypoint_student_is_labelled_with_the_subgoals_bearing_and_steers_the_field_there(make_env):
    """ClutterNav-v1's waypoint interface: the label is the planner's subgoal bearing in units of pi, and the field
    steering for a bearing equal to the goal's acts as the field on the goal."""
    import math

    from clutter_gym.training.residual import SubgoalResidual

    env = make_env("ClutterNav-v1", **{**SMALL, "subgoal_lookahead": 0.5})
    wrapped = SubgoalResidual(env, 0.0, space="waypoint")
    assert wrapped.action_space.shape == (1,)
    labelled = TeacherLabels(wrapped, make_teacher("ClutterNav-v1", "planner", wrapped, "waypoint"))
    obs, _ = labelled.reset(seed=4)
    field = PotentialFieldNavigator.for_env(env)
    goal_bearing = math.atan2(float(obs["goal"][1]), float(obs["goal"][2]))
    np.testing.assert_allclose(field.toward(obs, goal_bearing), field(obs), atol=1e-6)
    _, _, _, _, info = labelled.step(np.array([goal_bearing / math.pi], dtype=np.float32))
    subgoal = obs["subgoal"]
    np.testing.assert_allclose(info["teacher_action"], [math.atan2(subgoal[1], subgoal[2]) / math.pi], rtol=1e-6)


def test_the_seen_map_teacher_knows_more_as_it_sees_more_and_the_in_range_one_only_the_last_scan(make_env):
    kwargs = {"sensors": ["lidar"], "obstacle_density": 0.2, "reverse": False, "subgoal_lookahead": 0.5}
    known = {}
    for name in ("seen-map", "in-range"):
        env = make_env("ClutterNav-v1", **kwargs)
        labelled = TeacherLabels(env, make_teacher("ClutterNav-v1", name, env), teacher_share=1.0)
        labelled.reset(seed=7)
        sizes = []
        for _ in range(60):
            *_, terminated, truncated, _ = labelled.step(np.zeros(2, dtype=np.float32))
            sizes.append(len(labelled.teacher.known.seen))
            if terminated or truncated:
                break
        known[name] = sizes
    assert known["seen-map"] == sorted(known["seen-map"]) and known["seen-map"][-1] > known["seen-map"][0]
    assert all(s <= k for s, k in zip(known["in-range"], known["seen-map"]))
    assert known["in-range"] != sorted(known["in-range"])  # obstacles leave the last scan as the robot moves


@pytest.mark.parametrize("env_id", ["ClutterNav-v1", "ClutterFly-v1"])
def test_the_realisability_benchmark_drives_each_env_through_its_students_interface(env_id):
    """The teacher drives the shipped student's env as the student acts on it (ClutterNav: a waypoint the pursuit
    follows; ClutterFly: the flyer's velocity), so its success bounds what imitation of it can reach."""
    from helpers import run_benchmark

    done = run_benchmark("benchmarks.learning.teacher_realisability", "--env", env_id, "--episodes", "1",
                         "--teachers", "planner", "--levels", "0.05")
    assert done.returncode == 0, done.stderr[-2000:]
    assert re.search(r"^\| planner \| \d+% \[\d+%, \d+%\] / \d+% \|$", done.stdout, re.M), done.stdout


def test_the_waypoint_diagnosis_compares_a_students_waypoint_with_its_teachers_episode_by_episode():
    from helpers import run_benchmark

    done = run_benchmark("benchmarks.learning.waypoint_diagnosis", "--run", "pretrained/ClutterNav-v1-student",
                         "--episodes", "2")
    assert done.returncode == 0, done.stderr[-2000:]
    rows = re.findall(r"^\| 100000\d \| (success|timeout|collision) \| \d+ \| [\d.]+ \| \d+% \| \d+ deg, \d+ deg \|$",
                      done.stdout, re.M)
    assert len(rows) == 2, done.stdout


def test_on_clutterfly_the_waypoint_diagnosis_adds_the_elevation_gap_and_whether_it_ended_at_a_wall():
    from helpers import run_benchmark

    done = run_benchmark("benchmarks.learning.waypoint_diagnosis", "--run", "pretrained/ClutterFly-v1-student",
                         "--episodes", "1")
    assert done.returncode == 0, done.stderr[-2000:]
    assert re.search(r"^\| 1000000 \| (success|timeout|collision) \| \d+ \| [\d.]+ \| \d+% \| \d+ deg, \d+ deg \| "
                     r"\d+ deg \| (yes|no) \|$", done.stdout, re.M), done.stdout


def test_labels_sent_astray_are_the_teachers_rounded_to_the_bins_and_move_at_most_the_spread():
    from benchmarks.learning.teacher_realisability import Astray

    class Fixed(Teacher):
        def __call__(self, obs, info):
            return np.array([0.26, -1.0], dtype=np.float32)

    rounded = Astray(Fixed(), 5, share=0.0, spread=2)({}, {})
    np.testing.assert_array_equal(rounded, [0.5, -1.0])  # bins at -1, -0.5, 0, 0.5, 1
    astray = Astray(Fixed(), 5, share=1.0, spread=1)
    moved = np.array([astray({}, {}) for _ in range(200)])
    assert set(np.round(moved[:, 0], 6)) == {0.0, 0.5, 1.0} and set(np.round(moved[:, 1], 6)) == {-1.0, -0.5}


@pytest.mark.parametrize("dynamics", ["physics", "reduced"])
def test_the_seen_map_teacher_drives_from_where_the_dynamics_has_the_robot(make_env, dynamics):
    """Under the reduced model pybullet's bodies stay where the episode began; a teacher reading them planned from
    the start for the whole episode (2% success). It reads ``robot_state()``, the env's own state."""
    env = make_env("ClutterNav-v1", sensors=["lidar"], obstacle_density=0.05, reverse=False, subgoal_lookahead=0.5,
                   dynamics=dynamics)
    labelled = TeacherLabels(env, make_teacher("ClutterNav-v1", "seen-map", env), teacher_share=1.0)
    finished = []
    for seed in (3, 4):
        labelled.reset(seed=seed)
        while True:
            *_, terminated, truncated, info = labelled.step(np.zeros(2, dtype=np.float32))
            if terminated or truncated:
                break
        finished.append(info["is_success"])
    assert finished == [True, True]
