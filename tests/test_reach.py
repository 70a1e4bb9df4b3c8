"""ClutterReach-v1: layouts, user scenes and their errors, both control modes, reward terms, and the FCL/pybullet
cross-check (API and determinism are in test_api.py, parametrised over every env id)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from helpers import SHELF_SEED

from clutter_gym.collision.fidelity import COARSE_LEVELS, FIDELITY_LEVELS
from clutter_gym.datatypes import Obstacle
from clutter_gym.robots.panda import REACH_RADIUS, SHOULDER
from clutter_gym.training.baselines import ProximityFieldReacher, StraightLineReacher
from clutter_gym.worlds.table.sample import sample_reach_scene
from clutter_gym.worlds.table.scene import point_clearance
from clutter_gym.worlds.table.spec import TABLE, TableSpec

READY = [0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4]
READY_EE = np.array([0.307, 0.0, 0.485])  # panda_grasptarget at READY


def scene(obstacles=(), target=(0.45, 0.2, 0.3), start=READY) -> dict:
    return {"obstacles": list(obstacles), "start": list(start), "target": list(target)}


@pytest.mark.parametrize("fidelity", ["convex", "mesh"])
def test_generated_layouts_start_clear_with_a_free_reachable_target(fidelity, make_env):
    env = make_env("ClutterReach-v1", collision_fidelity=fidelity)
    for seed in range(25):
        obs, info = env.reset(seed=seed)
        scene_ = env.unwrapped.scene
        assert info["n_contacts"] == 0 and info["min_clearance"] > 0.0
        assert env.unwrapped.checker.check(env.unwrapped.robot.state()).self_collision is None
        assert point_clearance(np.array(scene_.target), scene_.obstacles) >= 0.06
        assert np.linalg.norm(np.array(scene_.target) - [0, 0, 0.333]) <= 0.8


@pytest.mark.parametrize("fidelity", FIDELITY_LEVELS)
def test_generated_scenes_are_accepted_back_at_every_fidelity_level(fidelity, make_env):
    """A generated start is clear of the clutter and of self-collision; a coarse level refused some of them back when
    it judged self-collision by its own shapes, which overlap around the wrist where the links do not."""
    env = make_env("ClutterReach-v1", collision_fidelity=fidelity)
    for seed in range(31):
        env.reset(seed=seed)
        _, info = env.reset(options={"scene": env.unwrapped.scene.to_dict()})
        assert info["n_contacts"] == 0


def test_coarse_levels_report_the_self_collisions_convex_reports_under_random_commands(make_env):
    """The fidelity level changes what FCL measures, not the physics: envs stepped in lockstep share every pose."""
    levels = ("convex", *COARSE_LEVELS)
    envs = {level: make_env("ClutterReach-v1", collision_fidelity=level, max_joint_speed=1.0) for level in levels}
    rng = np.random.default_rng(2)
    reports = {level: [] for level in levels}
    for seed in range(3):
        for env in envs.values():
            env.reset(seed=seed)
        for _ in range(100):
            action = rng.uniform(-1, 1, 7)
            for level, env in envs.items():
                reports[level].append(env.step(action)[4]["self_collision"] is not None)
    convex = np.array(reports["convex"])
    assert convex.sum() >= 10  # the arm folds onto itself in some steps
    for level in COARSE_LEVELS:
        coarse = np.array(reports[level])
        assert not np.any(coarse & ~convex), f"{level}: self-collision convex does not see"
        if level != "spheres":  # its sphere sets enclose the meshes, not their hulls: it can only see less
            np.testing.assert_array_equal(coarse, convex, err_msg=level)


def test_layouts_have_a_shelf_and_are_seeded():
    spec = TableSpec()
    a = sample_reach_scene(np.random.default_rng(4), spec, READY, SHOULDER, REACH_RADIUS)
    b = sample_reach_scene(np.random.default_rng(4), spec, READY, SHOULDER, REACH_RADIUS)
    assert a == b and len(a.obstacles) == spec.n_obstacles + 5
    assert any(o.z > 0 for o in a.obstacles)  # the shelf's boards


def test_user_scene_round_trips_and_starts_where_asked(make_env):
    env = make_env("ClutterReach-v1")
    env.reset(seed=9)
    layout = env.unwrapped.scene.to_dict()
    obs, _ = env.reset(options={"scene": layout})
    np.testing.assert_allclose(obs["joint_position"], layout["start"], atol=1e-6)
    np.testing.assert_allclose(obs["target"], layout["target"], atol=1e-6)
    assert env.unwrapped.scene.to_dict() == layout


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (scene(target=(2.0, 0.0, 0.3)), "scene.target .* beyond the arm's reach"),
        (scene(start=[0.0] * 6), r"scene.start must be a list of 7 numbers"),
        (scene(start=[0, 0, 0, 0.5, 0, 0, 0]), r"scene.start\[3\] must be in \[-3.1416, 0.0\]"),
        ({"target": [0.4, 0, 0.3], "goal": [1, 1]}, "scene has unknown keys \\['goal'\\]"),
        (scene([{"shape": "box", "size": [0.1, 0.1, 0.1], "position": [0.4, 0.0], "z": -1}]), r"z \(bottom height\)"),
        (scene([{"shape": "box", "size": [0.2, 0.2, 0.8], "position": [0.3, 0.0]}]), "scene starts in collision"),
    ],
)
def test_bad_scenes_raise_naming_the_field(bad, message, make_env):
    env = make_env("ClutterReach-v1")
    with pytest.raises(ValueError, match=message):
        env.reset(options={"scene": bad})


def test_a_scene_refused_for_starting_in_collision_cannot_be_stepped(make_env):
    """The refused scene is already placed when the check refuses it: a step there would run it anyway."""
    env = make_env("ClutterReach-v1")
    env.reset(seed=0)
    env.step(np.zeros(7))
    with pytest.raises(ValueError, match="scene starts in collision"):
        env.reset(options={"scene": scene([{"shape": "box", "size": [0.2, 0.2, 0.8], "position": [0.3, 0.0]}])})
    for _ in range(2):  # refused every time, not once
        with pytest.raises(RuntimeError, match=r"last reset\(\) failed \(ValueError: scene starts in collision.*"
                                               r"call reset\(\) again"):
            env.step(np.zeros(7))
    assert env.unwrapped.scene is None
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.zeros(7))
    assert info["cost"] == 0.0 and info["n_contacts"] == 0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"collision_fidelity": "voxel"}, "collision_fidelity must be one of"),
        ({"control": "torque"}, "control must be one of"),
        ({"max_joint_speed": 2.0}, r"max_joint_speed must be in \(0, 1\]"),
        ({"n_obstacles": 40}, r"n_obstacles must be an integer in \[0, 20\]"),
        ({"clearance_range": 0.0}, r"clearance_range must be in \[0.01, 2\]"),
        ({"clearance_margin": 0.5}, r"clearance_margin must be in \[0, clearance_range=0.3\]"),
        ({"collision_padding": -0.01}, "padding for link .* must be in"),
        ({"swept_speed": 0.0}, "swept_speed must be > 0"),
        ({"physics_hz": 250.0}, "physics_hz must be an integer multiple of control_hz"),
    ],
)
def test_bad_kwargs_raise_at_make(kwargs, message, make_env):
    with pytest.raises(ValueError, match=message):
        make_env("ClutterReach-v1", **kwargs)


def test_joint_velocity_actions_move_each_joint_by_speed_times_period(make_env):
    env = make_env("ClutterReach-v1", max_joint_speed=0.5)
    env.reset(options={"scene": scene()})
    action = np.zeros(7, dtype=np.float32)
    action[0] = 1.0  # joint 1 at half its 2.175 rad/s limit for 4 steps of 0.05 s, then hold
    for a in [action] * 4 + [np.zeros(7, dtype=np.float32)] * 6:
        obs, *_ = env.step(a)
    assert obs["joint_position"][0] == pytest.approx(4 * 0.05 * 0.5 * 2.175, abs=0.005)
    np.testing.assert_allclose(obs["joint_position"][1:], READY[1:], atol=0.01)


def test_ee_position_control_moves_the_hand_where_asked(make_env):
    env = make_env("ClutterReach-v1", control="ee_position")
    obs, _ = env.reset(options={"scene": scene()})
    start = obs["ee_position"].copy()
    for _ in range(6):
        obs, *_ = env.step(np.array([1.0, 0.0, -0.5], dtype=np.float32))  # 5 cm forward, 2.5 cm down per step
    np.testing.assert_allclose(obs["ee_position"] - start, [0.3, 0.0, -0.15], atol=0.03)


def test_reaching_the_target_is_a_success_with_the_bonus(make_env):
    target = READY_EE + [0.1, 0.0, -0.05]
    env = make_env("ClutterReach-v1", control="ee_position")
    obs, _ = env.reset(options={"scene": scene(target=target)})
    for _ in range(20):
        step = np.clip((obs["target"] - obs["ee_position"]) / 0.05, -1, 1)
        obs, reward, terminated, _, info = env.step(step)
        if terminated:
            break
    assert info["is_success"] and info["reward_terms"]["success"] == 10.0 and info["cost"] == 0.0


def test_pressing_into_a_box_is_a_contact_both_engines_see_and_costs(make_env):
    box = {"shape": "box", "size": [0.3, 0.4, 0.3], "position": [0.35, 0.0]}  # top at 0.3 m, under the hand
    env = make_env("ClutterReach-v1", control="ee_position")
    env.reset(options={"scene": scene([box])})
    infos = [env.step(np.array([0.0, 0.0, -1.0], dtype=np.float32))[4] for _ in range(8)]
    touching = [i for i in infos if i["n_contacts"] > 0]
    assert touching and all(i["cost"] == 1.0 and i["reward_terms"]["contact"] == -1.0 for i in touching)
    assert all(i["pybullet_contacts"] > 0 for i in touching[1:])  # pybullet sees it too once pressed
    assert min(i["min_clearance"] for i in infos) < 0.0


def test_clearance_observation_matches_the_witness_points(make_env):
    obstacle = {"shape": "cylinder", "radius": 0.05, "height": 0.3, "position": [0.3, 0.3]}
    env = make_env("ClutterReach-v1", observe_directions=True)
    obs, _ = env.reset(options={"scene": scene([obstacle])})
    obs, _, _, _, info = env.step(np.zeros(7, dtype=np.float32))
    points = info["witness_points"]
    assert np.linalg.norm(points[1] - points[0]) == pytest.approx(info["min_clearance"], abs=1e-6)
    obstacles = (Obstacle("cylinder", (0.1, 0.1, 0.3), (0.3, 0.3)), TABLE)
    assert abs(obstacles[info["closest_pair"][1]].distance3d(points[1])) < 1e-6  # on the obstacle's surface
    assert min(obs["clearance"]) == pytest.approx(info["min_clearance"], abs=1e-6)
    link = env.unwrapped.checker.links.index(info["closest_pair"][0])
    gap = points[1] - points[0]
    np.testing.assert_allclose(obs["clearance_direction"][link], gap / np.linalg.norm(gap), atol=1e-5)


def test_fcl_and_pybullet_agree_on_contact_in_most_random_steps(make_env):
    """Measured: 98% agreement (8 of 480 steps differ, all pybullet-only: its contact points reach out to its
    collision margin while FCL's clearance is still above the 1 mm tolerance); 1 of these 240. The steps in contact
    move with any change to the hand's path: 50 of 240 with the IK target read in float32, 40 in float64 (the two
    targets differ by under 3e-8 m), so the floor only checks that the rollouts touch things."""
    env = make_env("ClutterReach-v1", control="ee_position", n_obstacles=12)
    rng = np.random.default_rng(0)
    steps = disagreements = contacts = 0
    for seed in range(4):
        env.reset(seed=seed)
        action = np.zeros(3)
        for _ in range(60):  # a random walk of the hand, drifting down among the clutter
            action = np.clip(0.7 * action + 0.6 * rng.normal(size=3) + [0, 0, -0.15], -1, 1)
            info = env.step(action)[4]
            steps += 1
            disagreements += info["contact_disagreement"]
            contacts += info["n_contacts"] > 0
    assert contacts > 20  # the rollouts do touch things
    assert disagreements / steps < 0.05


def test_obstacle_distance3d_closed_forms():
    box = Obstacle("box", (0.2, 0.4, 0.3), (1.0, 0.0), math.pi / 2, 0.1)  # rotated: 0.4 along x, 0.2 along y
    assert box.distance3d(np.array([1.5, 0.0, 0.25])) == pytest.approx(0.3)
    assert box.distance3d(np.array([1.0, 0.0, 0.0])) == pytest.approx(0.1)  # below its bottom at z = 0.1
    assert box.distance3d(np.array([1.0, 0.0, 0.25])) == pytest.approx(-0.1)  # inside: nearest face 0.1 away
    corner = np.array([1.2, 0.1, 0.4]) + [0.03, 0.04, 0.0]
    assert box.distance3d(corner) == pytest.approx(0.05)
    cylinder = Obstacle("cylinder", (0.2, 0.2, 0.5), (0.0, 0.0))
    assert cylinder.distance3d(np.array([0.4, 0.0, 0.8])) == pytest.approx(math.hypot(0.3, 0.3))


def test_straight_line_reacher_reaches_every_target_on_an_empty_table():
    env = gym.make("ClutterReach-v1", control="ee_position", n_obstacles=0, shelf=False)
    reacher = StraightLineReacher.for_env(env)
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        for _ in range(30):
            obs, _, terminated, _, info = env.step(reacher(obs))
            assert info["cost"] == 0.0
            if terminated:
                break
        assert info["is_success"], f"seed {seed}: the straight line to the target missed"
    env.close()


def test_straight_line_reacher_refuses_joint_velocity_control():
    with pytest.raises(ValueError, match="control='ee_position'"):
        StraightLineReacher.for_env(gym.make("ClutterReach-v1"))


def _field_obs(q, target, readings=()):
    """An observation for the proximity field at joint positions ``q``: no link reads an obstacle, except
    ``readings`` as (link row, distance, unit direction towards the obstacle)."""
    obs = {"joint_position": np.asarray(q, dtype=np.float32), "target": np.asarray(target, dtype=np.float32),
           "clearance": np.full(10, 0.3, dtype=np.float32), "clearance_direction": np.zeros((10, 3), np.float32)}
    for row, distance, direction in readings:
        obs["clearance"][row], obs["clearance_direction"][row] = distance, direction
    return obs


def _field_motion(field, q, action, point_of):
    """How far a point of the arm moves in 1 ms of the field's joint velocities (finite differences of the FK)."""
    from clutter_gym.robots.panda import FINGER_OPENING

    rates = action.astype(float) * field.speed_scale
    frames = [field.kinematics.forward(np.concatenate([q + dt * rates, [FINGER_OPENING] * 2])[None])
              for dt in (0.0, 1e-3)]
    return (point_of(frames[1]) - point_of(frames[0])) / 1e-3


def test_proximity_field_drives_the_end_effector_straight_at_the_target_in_free_space():
    """Damped least squares: the end effector's velocity is attraction x offset, up to the damping's share
    lambda^2 / (sigma^2 + lambda^2) <= 3% at READY (smallest singular value of the position Jacobian ~0.3 m)."""
    field = ProximityFieldReacher(max_joint_speed=0.5)
    q = np.array(READY)
    for offset in ([0.08, 0.0, 0.0], [0.0, -0.06, 0.04], [-0.05, 0.03, -0.07]):
        action = field(_field_obs(q, READY_EE + offset))
        assert np.abs(action).max() < 1.0  # unclipped: the joint rates are the field's own
        velocity = _field_motion(field, q, action, lambda f: f["panda_grasptarget"][0, :3, 3])
        wanted = field.attraction * np.array(offset)
        assert np.dot(velocity, wanted) / (np.linalg.norm(velocity) * np.linalg.norm(wanted)) > 0.999
        assert np.linalg.norm(velocity) == pytest.approx(np.linalg.norm(wanted), rel=0.03)
    far = field(_field_obs(q, READY_EE + [0.0, 0.5, 0.0]))
    velocity = _field_motion(field, q, far, lambda f: f["panda_grasptarget"][0, :3, 3])
    assert np.linalg.norm(velocity) == pytest.approx(field.top_speed, rel=0.03)  # capped
    batch = {k: np.stack([v, v]) for k, v in _field_obs(q, READY_EE + [0.08, 0.0, 0.0]).items()}
    np.testing.assert_array_equal(field(batch)[1], field(_field_obs(q, READY_EE + [0.08, 0.0, 0.0])))


def test_proximity_field_pushes_a_near_link_away_from_its_obstacle_and_ignores_a_far_one():
    from clutter_gym.robots.panda import FINGER_OPENING

    field = ProximityFieldReacher(max_joint_speed=0.5)
    q = np.array(READY)
    ee = field.kinematics.forward(np.concatenate([q, [FINGER_OPENING] * 2])[None])["panda_grasptarget"][0, :3, 3]
    towards = np.array([0.0, 0.6, 0.8])
    for row, link, beyond in ((3, "panda_link4", "panda_link5"), (7, "panda_hand", "panda_grasptarget")):
        action = field(_field_obs(q, ee, [(row, 0.02, towards)]))  # the target where the hand is: no attraction
        assert np.abs(action).max() > 0.05
        motion = _field_motion(field, q, action, lambda f, a=link, b=beyond: 0.5 * (f[a][0, :3, 3] + f[b][0, :3, 3]))
        assert np.dot(motion, -towards) > 0.5 * np.linalg.norm(motion)  # mostly straight away from the obstacle
        unread = field(_field_obs(q, ee, [(row, field.influence, towards)]))
        np.testing.assert_allclose(unread, 0.0, atol=1e-6)


def test_proximity_field_touches_nothing_where_it_would_without_its_readings(make_env):
    """On layouts where the field without repulsion (the straight joint-space line) touches the clutter, the
    proximity readings keep the arm clear of it."""
    env = make_env("ClutterReach-v1", observe_directions=True)
    for seed in (SHELF_SEED, SHELF_SEED + 2):
        touched = []
        for field in (ProximityFieldReacher.for_env(env, repulsion=0.0), ProximityFieldReacher.for_env(env)):
            obs, _ = env.reset(seed=seed)
            costs = []
            for _ in range(100):
                obs, _, _, _, info = env.step(field(obs))
                costs.append(info["cost"])
            touched.append(max(costs) > 0.0)
        assert touched == [True, False], f"layout {seed}"
    with pytest.raises(ValueError, match="observe_directions=True"):
        ProximityFieldReacher.for_env(make_env("ClutterReach-v1"))


def test_target_offset_is_opt_in_and_equals_target_minus_end_effector():
    assert "target_offset" not in gym.make("ClutterReach-v1").observation_space.spaces
    env = gym.make("ClutterReach-v1", control="ee_position", observe_target_offset=True)
    obs, _ = env.reset(seed=3)
    for _ in range(3):
        assert env.observation_space.contains(obs)
        np.testing.assert_allclose(obs["target_offset"], obs["target"] - obs["ee_position"], atol=1e-6)
        obs, *_ = env.step(np.array([0.5, -0.5, 0.2], dtype=np.float32))
    env.close()


def test_padding_is_a_margin_against_the_world_not_between_the_arms_own_links():
    """panda_link5 and panda_link7 sit about 22 mm apart in every start pose: padded 1 cm each, they touched, and from
    about 11 mm of padding every episode started in self-collision and every generated scene was refused back."""
    env = gym.make("ClutterReach-v1", collision_padding=0.02)
    for seed in range(5):
        _, info = env.reset(seed=seed)
        model = env.unwrapped.checker.model
        assert model.self_collision() is None
        env.reset(options={"scene": env.unwrapped.scene.to_dict()})  # accepted back
    env.close()
