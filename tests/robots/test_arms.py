"""Arms in ClutterReach-v1 by ``robot=``: the KUKA iiwa and the xArm6 from pybullet_data, and an arm spec's refusals."""

from __future__ import annotations

import shutil

import gymnasium as gym
import numpy as np
import pytest

from clutter_gym.robots.arm_model import arm_from_spec
from clutter_gym.robots.registry import registered
from clutter_gym.sim import pybullet_data_file
from clutter_gym.training.baselines import StraightLineReacher
from clutter_gym.training.joint_planner import JointPlannerReacher
from clutter_gym.util.quiet import quiet_c_output

with quiet_c_output():
    import pybullet as pb

ARMS = ("kuka_iiwa", "xarm6")
#: The level whose shapes are pybullet's own: its convex hull of each single-mesh link (the Panda, the iiwa), or the
#: convex pieces of the xArm's decomposed meshes (which FCL's ``mesh`` level models triangle for triangle).
PYBULLETS_LEVEL = {"panda": "convex", "kuka_iiwa": "convex", "xarm6": "mesh"}


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def test_the_arms_are_registered_and_clutterreach_takes_them():
    assert registered("arm") == ["panda", *ARMS]
    with pytest.raises(ValueError, match=r"ClutterReach-v1 takes a fixed-base arm: robot= one of \['panda', "
                                         r"'kuka_iiwa', 'xarm6'\], or a spec with kind 'arm'"):
        gym.make("ClutterReach-v1", robot="husky")


@pytest.mark.parametrize("robot, n", [("kuka_iiwa", 7), ("xarm6", 6)])
def test_each_arm_passes_the_env_checks_with_its_own_joint_count(robot, n, tmp_path):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("ClutterReach-v1", robot=robot)
    assert env.action_space.shape == (n,) and env.observation_space["joint_position"].shape == (n,)
    check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)
    env.close()
    assert not (tmp_path / "cache" / "clutter-gym" / "acm").exists()  # the shipped ACMs match: none generated


@pytest.mark.parametrize("robot", ARMS)
def test_each_arm_replays_its_seeded_trajectory_in_lockstep(robot):
    envs = [gym.make("ClutterReach-v1", robot=robot) for _ in range(2)]
    for env in envs:
        env.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(40):
        action = rng.uniform(-1, 1, envs[0].action_space.shape)
        a, b = (env.step(action) for env in envs)
        for key in a[0]:
            np.testing.assert_array_equal(a[0][key], b[0][key])
        assert a[1:4] == b[1:4]
    for env in envs:
        env.close()


@pytest.mark.parametrize("robot", ARMS)
def test_each_arm_reaches_every_target_on_an_empty_table_and_plans_among_clutter(robot):
    env = gym.make("ClutterReach-v1", robot=robot, control="ee_position", n_obstacles=0, shelf=False)
    for seed in range(4):
        obs, _ = env.reset(seed=seed)
        reacher = StraightLineReacher.for_env(env)
        for _ in range(200):
            obs, _, terminated, truncated, info = env.step(reacher(obs))
            if terminated or truncated:
                break
        assert info["is_success"], (robot, seed)
    env.close()
    env = gym.make("ClutterReach-v1", robot=robot, subgoal_lookahead=0.1)
    obs, _ = env.reset(seed=1)
    assert obs["subgoal"].shape == env.action_space.shape and np.abs(obs["subgoal"]).max() > 0.0
    env.close()
    env = gym.make("ClutterReach-v1", robot=robot)
    planner, successes = JointPlannerReacher(env, seed=0), 0
    for seed in range(100, 104):
        obs, _ = env.reset(seed=seed)
        while True:
            obs, _, terminated, truncated, info = env.step(planner(obs))
            assert info["n_contacts"] == 0
            if terminated or truncated:
                break
        successes += info["is_success"]
    assert planner.planned >= 2 and successes == planner.planned
    env.close()


@pytest.mark.parametrize("robot", ["panda", *ARMS])
def test_fcl_and_pybullet_agree_on_each_arms_clearance(robot):
    """At random configurations with clearance in (0, 0.3) m, at the level whose shapes are pybullet's, FCL's
    clearance exceeds pybullet's closest distance (which takes off its 1 mm collision margin) by 0 to 1.2 mm, the
    band the Panda meets: measured 0.27-1.05 mm for each of the three arms, boxes and cylinders alike. The xArm at
    ``convex`` differs by up to 20 mm, where a hull fills its meshes' hollows."""
    env = gym.make("ClutterReach-v1", robot=robot, collision_fidelity=PYBULLETS_LEVEL[robot], n_obstacles=12)
    u = env.unwrapped
    model, rng, gaps = u.robot.model, np.random.default_rng(0), []
    bolted = {u.robot.link_index[link] for link in model.fixed_links} | {-1}
    for i in range(200):
        if i % 25 == 0:
            env.reset(seed=i)
        u.robot.reset_to(tuple(rng.uniform(model.lower, model.upper)))
        report = u.checker.check(u.robot.state(), u.sim.contact_distances(u.robot.body))
        points = [c[8] for body in u.checker._obstacle_bodies
                  for c in pb.getClosestPoints(u.robot.body, body, 0.3, physicsClientId=u.sim.client_id)
                  if c[3] not in bolted]
        if points and report.self_collision is None and 0.0 < report.min_clearance < 0.3:
            gaps.append(report.min_clearance - min(points))
    env.close()
    assert len(gaps) > 80
    assert 0.0 <= min(gaps) and max(gaps) <= 1.2e-3


SPEC = {"kind": "arm", "urdf": str(pybullet_data_file("kuka_iiwa/model.urdf")),
        "arm_joints": [f"lbr_iiwa_joint_{i}" for i in range(1, 8)], "ee_link": "lbr_iiwa_link_7",
        "ready": [0.0, -0.05, 0.0, -2.0, 0.0, 1.19, 0.0]}


@pytest.mark.parametrize("change, message", [
    ({"ee_link": "tool"}, r"ee_link 'tool' is not a link of .*model.urdf; add it with ee_mount or pick one of "
                          r"\['lbr_iiwa_link_0'"),
    ({"ready": [0.0] * 6}, r"ready must be 7 numbers"),
    ({"ready": [0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0]}, r"ready \[0.0, 3.0, .*\] is outside the joint limits"),
    ({"arm_joints": ["lbr_iiwa_joint_1", "j2", "j3"]}, r"arm_joints names \['j2', 'j3'\], not moving joints"),
    ({"speed_limits": [1.0] * 7 + [2.0]}, r"speed_limits must be 7 numbers in \[0.01, 20\]"),
    ({"arm_joints": "lbr_iiwa_joint_1"}, r"arm_joints must be a list of 3 to 9 joint names"),
    ({"gripper": True}, r"unknown keys \['gripper'\]; an arm spec takes"),
])
def test_a_bad_arm_spec_is_refused_naming_the_key(change, message):
    with pytest.raises(ValueError, match=message):
        arm_from_spec({**SPEC, **change}, "spec")


JOINT_7 = '<limit effort="300" lower="-3.05432619099" upper="3.05432619099" velocity="10"/>'


def kuka_with(tmp_path, old: str, new: str) -> str:
    """pybullet_data's iiwa with ``old`` (found once) replaced by ``new``, beside a copy of its meshes (a spec's
    meshes must lie in its URDF's folder)."""
    source = pybullet_data_file("kuka_iiwa/model.urdf")
    text = source.read_text()
    assert text.count(old) == 1
    shutil.copytree(source.parent / "meshes", tmp_path / "meshes")
    path = tmp_path / "kuka.urdf"
    path.write_text(text.replace(old, new))
    return str(path)


@pytest.mark.parametrize("old, new, message", [
    ('<joint name="lbr_iiwa_joint_7" type="revolute">', '<joint name="lbr_iiwa_joint_7" type="prismatic">',
     r"arm_joints 'lbr_iiwa_joint_7' of .*kuka.urdf is prismatic; an arm spec takes revolute and continuous joints"),
    (JOINT_7, JOINT_7.replace('lower="-3.05432619099" upper="3.05432619099"', 'lower="3.05" upper="-3.05"'),
     r"arm_joints 'lbr_iiwa_joint_7' of .*kuka.urdf has <limit lower=3.05 upper=-3.05> \(0 where not given\): an arm "
     r"joint needs lower < upper, in radians"),
    (JOINT_7, JOINT_7.replace('lower="-3.05432619099"', 'lower="nan"'),
     r"the URDF was refused: .*kuka.urdf: joint 'lbr_iiwa_joint_7' <limit> lower: expected 1 finite number, got "
     r"'nan'"),
    (JOINT_7, JOINT_7.replace(' velocity="10"', ""),
     r"speed_limits was not given, and .*kuka.urdf gives no <limit velocity=...> for \['lbr_iiwa_joint_7'\]: give "
     r"speed_limits in the spec"),
])
def test_an_arm_joint_the_arm_cannot_drive_is_refused_naming_it(tmp_path, old, new, message):
    """Before: a prismatic joint was accepted (its observations left the observation space), a NaN limit was
    accepted, inverted limits were blamed on the ready pose, and a missing velocity limit gave speed_limits "got
    [..., nan]" for a key the spec never wrote."""
    with pytest.raises(ValueError, match=rf"^spec: {message}"):
        arm_from_spec({**SPEC, "urdf": kuka_with(tmp_path, old, new)}, "spec")


@pytest.mark.parametrize("ee_link, what", [("lbr_iiwa_link_0", "the root link"),
                                           ("tool", "bolted to the root link")])
def test_an_end_effector_no_arm_joint_moves_is_refused_at_make(ee_link, what):
    """Before: an ``ee_link`` at the root was accepted at make and failed only at reset."""
    spec = {**SPEC, "ee_link": ee_link}
    if ee_link == "tool":
        spec["ee_mount"] = {"parent": "lbr_iiwa_link_0", "xyz": [0.0, 0.0, 0.1]}
    with pytest.raises(ValueError, match=rf"^spec: ee_link '{ee_link}' is {what} of .*model.urdf: no arm joint moves "
                                         r"it; pick a link past the last arm joint"):
        arm_from_spec(spec, "spec")


def test_an_arm_whose_urdf_has_more_moving_joints_is_refused():
    with pytest.raises(ValueError, match=r"has moving joints \['panda_finger_joint1', 'panda_finger_joint2'\] "
                                         r"besides arm_joints"):
        arm_from_spec({"kind": "arm", "urdf": str(pybullet_data_file("franka_panda/panda.urdf")),
                       "arm_joints": [f"panda_joint{i}" for i in range(1, 8)], "ee_link": "panda_hand",
                       "ready": [0.0, -0.78, 0.0, -2.36, 0.0, 1.57, 0.78]}, "spec")


def test_a_user_arm_spec_drives_in_clutterreach():
    env = gym.make("ClutterReach-v1", robot=SPEC)
    assert env.unwrapped.robot.name == "model" and env.action_space.shape == (7,)
    env.reset(seed=0)
    for _ in range(5):
        env.step(env.action_space.sample())
    env.close()
