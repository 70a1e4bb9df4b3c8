"""Robots chosen by ``robot=``: the registry's refusals, the prepared URDF, a base read from a spec, the Husky.
Multirotor specs: test_multirotor_spec.py."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import gymnasium as gym
import numpy as np
import pybullet_data
import pytest

from clutter_gym.assets import asset_path
from clutter_gym.robots.registry import register_robot, registered
from clutter_gym.robots.urdf_prep import TOKEN_MASS, Mount, prepared_urdf
from clutter_gym.robots.wheeled import diffbot, wheeled_base_from_spec
from clutter_gym.util.quiet import quiet_c_output

with quiet_c_output():
    import pybullet as pb

HUSKY = Path(pybullet_data.getDataPath()) / "husky" / "husky.urdf"
DIFFBOT_SPEC = {"kind": "diff_drive", "urdf": str(asset_path("robots/diffbot.urdf")),
                "left_wheels": ["left_wheel_joint"], "right_wheels": ["right_wheel_joint"]}


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # prepared URDFs land here, not in ~/.cache


# -- the registry -----------------------------------------------------------------------------------------------

def test_each_env_takes_its_kind_and_names_the_robots_it_takes():
    assert registered("diff_drive") == ["diffbot", "husky"]
    assert registered("arm") == ["panda", "kuka_iiwa", "xarm6"] and registered("multirotor") == ["quadrotor"]
    assert registered("omni") == ["omnibot"]
    with pytest.raises(ValueError, match=r"'panda' is a fixed-base arm; ClutterNav-v1 takes a wheeled base or "
                                         r"omnidirectional base: robot= one of \['diffbot', 'husky', 'omnibot'\], "
                                         r"or a spec with kind 'diff_drive' or 'omni'"):
        gym.make("ClutterNav-v1", robot="panda")
    with pytest.raises(ValueError, match=r"unknown robot 'nope'; ClutterFly-v1 takes a multirotor: robot= one of "
                                         r"\['quadrotor'\], or a spec with kind 'multirotor'$"):
        gym.make("ClutterFly-v1", robot="nope")
    with pytest.raises(ValueError, match=r"robot: missing 'rotor_links' \(a multirotor spec needs \['urdf'"):
        gym.make("ClutterFly-v1", robot={"kind": "multirotor", "urdf": "drone.urdf"})
    with pytest.raises(ValueError, match="kind 'arm' does not fit; ClutterNav-v1 takes a wheeled base"):
        gym.make("ClutterNav-v1", robot={"kind": "arm", "urdf": "arm.urdf"})


def test_a_registered_spec_is_read_when_an_env_first_asks_for_it(monkeypatch):
    from clutter_gym.robots import registry

    monkeypatch.setattr(registry, "_ROBOTS", dict(registry._ROBOTS))  # the test's registrations end with it
    register_robot("my_bot", "diff_drive", {**DIFFBOT_SPEC, "name": "my_bot", "wheel_radius": 0.0})
    with pytest.raises(ValueError, match=r"robot 'my_bot': wheel_radius must be a number in \[0.005, 2\], got 0.0"):
        gym.make("ClutterNav-v1", robot="my_bot")
    with pytest.raises(ValueError, match="a robot named 'husky' is already registered"):
        register_robot("husky", "diff_drive", DIFFBOT_SPEC)
    with pytest.raises(ValueError, match=r"robot kind must be one of \['diff_drive', 'omni', 'arm', 'multirotor'\]"):
        register_robot("boat", "boat", DIFFBOT_SPEC)
    assert "my_bot" in registered("diff_drive")


def test_the_default_robots_are_todays():
    env = gym.make("ClutterNav-v1")
    assert env.unwrapped.robot.base == diffbot()
    env.close()
    for env_id, robot in (("ClutterReach-v1", "panda"), ("ClutterFly-v1", "quadrotor")):
        env = gym.make(env_id, robot=robot)
        assert env.unwrapped.robot.name == robot
        env.close()


# -- the prepared URDF ------------------------------------------------------------------------------------------

def test_the_prepared_husky_resolves_xacro_defaults_weighs_massless_links_and_carries_its_mounts():
    path = prepared_urdf(HUSKY, "husky", (Mount("lidar_link", "base_link", (0.25, 0.0, 0.45)),))
    assert prepared_urdf(HUSKY, "husky", (Mount("lidar_link", "base_link", (0.25, 0.0, 0.45)),)) == path  # cached
    root = ET.parse(path).getroot()
    imu = next(j for j in root.findall("joint") if j.get("name") == "imu_joint").find("origin")
    assert imu.get("rpy") == "0 -1.5708 3.1416" and imu.get("xyz") == "0.19 0 0.149"  # the optenv defaults
    links = {link.get("name"): link for link in root.findall("link")}
    assert float(links["top_plate_link"].find("inertial/mass").get("value")) == TOKEN_MASS
    assert float(links["base_link"].find("inertial/mass").get("value")) == pytest.approx(33.455)  # kept
    lidar = next(j for j in root.findall("joint") if j.get("name") == "lidar_link_joint")
    assert lidar.find("parent").get("link") == "base_link" and lidar.find("origin").get("xyz") == "0.25 0.0 0.45"
    assert (path.parent / "meshes" / "wheel.stl").read_bytes() == (HUSKY.parent / "meshes" / "wheel.stl").read_bytes()
    client = pb.connect(pb.DIRECT)
    try:  # pybullet weighs it as the URDF says: 33.455 + 4 x 2.637 kg, not 6 kg more
        body = pb.loadURDF(str(path), physicsClientId=client)
        masses = [pb.getDynamicsInfo(body, i, physicsClientId=client)[0] for i in range(-1, pb.getNumJoints(
            body, physicsClientId=client))]
        assert sum(masses) == pytest.approx(33.455 + 4 * 2.637, abs=0.02)
    finally:
        pb.disconnect(client)


def test_a_mount_on_a_missing_link_or_over_an_existing_one_is_refused():
    with pytest.raises(ValueError, match=r"no link 'top' to mount 'lidar_link' on; its links: \['base_footprint'"):
        prepared_urdf(HUSKY, "husky", (Mount("lidar_link", "top"),))
    with pytest.raises(ValueError, match="already has a link 'imu_link'"):
        prepared_urdf(HUSKY, "husky", (Mount("imu_link", "base_link"),))


# -- a base from a spec -----------------------------------------------------------------------------------------

def test_the_diffbot_read_from_a_spec_is_the_built_in_one():
    """Wheel radius, track, base height and footprint, read from the URDF, are the numbers the diffbot was written
    with (the footprint to the 0.01% the rim sampling leaves: it is an enclosing bound)."""
    base, built_in = wheeled_base_from_spec(DIFFBOT_SPEC, "spec"), diffbot()
    assert base.wheel_radius == built_in.wheel_radius and base.wheel_separation == pytest.approx(0.29, abs=1e-12)
    assert base.base_height == built_in.base_height and base.base_link == "base_link"
    assert built_in.footprint_radius <= base.footprint_radius <= built_in.footprint_radius * 1.0002
    assert set(built_in.tracked_links) <= set(base.tracked_links)


@pytest.mark.parametrize("change, message", [
    ({"left_wheels": ["left_wheel"]}, r"left_wheels names \['left_wheel'\], not moving joints of .*diffbot.urdf; "
                                      r"its moving joints: \['left_wheel_joint', 'right_wheel_joint'\]"),
    ({"right_wheels": "right_wheel_joint"}, r"right_wheels must be a list of 1 to 16 joint names"),
    ({"wheel_radius": -1}, r"wheel_radius must be a number in \[0.005, 2\], got -1"),
    ({"max_wheel_torque": "strong"}, r"max_wheel_torque must be a number in \[0.01, 500\]"),
    ({"wheels": 4}, r"unknown keys \['wheels'\]; a diff_drive spec takes \['urdf'"),
    ({"urdf": "nowhere.urdf"}, "urdf 'nowhere.urdf' is not a file"),
    ({"mounts": {"lidar_link": {"parent": "base_link", "xyz": [0, 0]}}}, r"mounts.lidar_link.xyz must be 3 numbers"),
])
def test_a_bad_spec_is_refused_naming_the_key_and_what_the_urdf_offers(change, message):
    with pytest.raises(ValueError, match=message):
        wheeled_base_from_spec({**DIFFBOT_SPEC, **change}, "spec")
    spec = dict(DIFFBOT_SPEC)
    del spec["left_wheels"]
    with pytest.raises(ValueError, match="missing 'left_wheels'"):
        wheeled_base_from_spec(spec, "spec")


def test_a_urdf_the_parser_refuses_and_a_base_without_sensor_links_are_reported_as_such(tmp_path):
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='r'><link name='a'>")
    with pytest.raises(ValueError, match="the URDF was refused: cannot parse URDF"):
        wheeled_base_from_spec({**DIFFBOT_SPEC, "urdf": str(broken)}, "spec")
    with pytest.raises(ValueError, match=r"husky.urdf has no \['lidar_link', 'camera_link'\]; add them with mounts"):
        wheeled_base_from_spec({"kind": "diff_drive", "urdf": str(HUSKY), "left_wheels": ["front_left_wheel"],
                                "right_wheels": ["front_right_wheel"]}, "spec")


def test_a_yaml_spec_file_with_a_relative_urdf_drives_in_clutternav(tmp_path):
    (tmp_path / "robots").mkdir()
    urdf = tmp_path / "robots" / "mybot.urdf"
    urdf.write_bytes(asset_path("robots/diffbot.urdf").read_bytes())
    spec = tmp_path / "mybot.yaml"
    spec.write_text("kind: diff_drive\nname: mybot\nurdf: robots/mybot.urdf\nleft_wheels: [left_wheel_joint]\n"
                    "right_wheels: [right_wheel_joint]\nmax_wheel_torque: 1.5\n")
    env = gym.make("ClutterNav-v1", robot=str(spec))
    assert env.unwrapped.robot.name == "mybot"
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array([1.0, 0.0]))
    env.close()
    spec.write_text("- not a mapping\n")
    with pytest.raises(ValueError, match="expected a mapping of keys, got list"):
        gym.make("ClutterNav-v1", robot=str(spec))
    with pytest.raises(ValueError, match="robot spec file .*nope.yaml' not found"):
        gym.make("ClutterNav-v1", robot=str(tmp_path / "nope.yaml"))


def test_a_spec_file_in_capitals_is_read_and_a_binary_one_refused_in_one_line(tmp_path):
    """Before: ``robot.YAML`` was an "unknown robot", a binary file gave a raw UnicodeDecodeError, and a YAML error
    spread over several lines."""
    spec = tmp_path / "MYBOT.YAML"
    spec.write_text(f"kind: diff_drive\nurdf: {asset_path('robots/diffbot.urdf')}\nleft_wheels: [left_wheel_joint]\n"
                    "right_wheels: [right_wheel_joint]\n")
    env = gym.make("ClutterNav-v1", robot=str(spec))
    assert env.unwrapped.robot.name == "diffbot"
    env.close()
    spec.write_bytes(bytes(range(256)))
    with pytest.raises(ValueError, match=r"^robot spec file .*MYBOT.YAML is not UTF-8 text \(is it a YAML file\?\)$"):
        gym.make("ClutterNav-v1", robot=str(spec))
    spec.write_text("kind: [diff_drive\n")
    with pytest.raises(ValueError, match=r"^robot spec file .*MYBOT.YAML is not valid YAML: while parsing a flow "
                                         r"sequence [^\n]*$"):
        gym.make("ClutterNav-v1", robot=str(spec))


def test_a_urdf_given_as_the_robot_is_pointed_to_a_spec():
    with pytest.raises(ValueError, match=r"robot '.*diffbot.urdf' is a URDF: robot= takes its spec, e.g. \{'kind': "
                                         r"'diff_drive', 'urdf': '.*diffbot.urdf', ...\} \(docs/robots.md\)"):
        gym.make("ClutterNav-v1", robot=str(asset_path("robots/diffbot.urdf")))


def test_a_sensor_without_its_link_is_refused_at_make():
    spec = {**DIFFBOT_SPEC, "urdf": str(HUSKY), "left_wheels": ["front_left_wheel", "rear_left_wheel"],
            "right_wheels": ["front_right_wheel", "rear_right_wheel"],
            "mounts": {"lidar_link": {"parent": "base_link", "xyz": [0, 0, 0.4]}}}
    with pytest.raises(ValueError, match=r"robot 'husky' has no \['camera_link'\] for sensors"):
        gym.make("ClutterNav-v1", robot=spec, sensors=("lidar", "camera"))


# -- the Husky --------------------------------------------------------------------------------------------------

def test_the_husky_passes_gymnasiums_and_sb3s_env_checks():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("ClutterNav-v1", robot="husky")
    check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)
    env.close()


def test_the_husky_replays_its_seeded_trajectory_in_lockstep():
    envs = [gym.make("ClutterNav-v1", robot="husky") for _ in range(2)]
    observations = [env.reset(seed=5)[0] for env in envs]
    rng = np.random.default_rng(1)
    for _ in range(60):
        action = rng.uniform(-1, 1, 2)
        steps = [env.step(action) for env in envs]
        for key in observations[0]:
            np.testing.assert_array_equal(steps[0][0][key], steps[1][0][key])
        assert steps[0][1:4] == steps[1][1:4]
    for env in envs:
        env.close()


def test_the_husky_drives_at_the_commanded_speed_and_turns_on_the_spot():
    """Open floor: 0.5 m/s forward within 3% after two seconds. The skid-steer turn slips: a commanded 1 rad/s spin
    turns at about half that (measured 0.53 rad/s) and walks (0.28 m in 2 s: the centre of mass sits 8.7 cm behind
    the wheels' centre, so the rear wheels grip harder), but stays within its own footprint."""
    env = gym.make("ClutterNav-v1", robot="husky", arena_size=10.0)
    scene = {"obstacles": [], "start": [-3.0, 0.0, 0.0], "goal": [4.0, 0.0]}
    obs, _ = env.reset(seed=0, options={"scene": scene})
    for _ in range(40):
        obs = env.step(np.array([1.0, 0.0]))[0]
    assert obs["velocity"][0] == pytest.approx(0.5, rel=0.03)
    env.reset(seed=0, options={"scene": scene})
    for _ in range(40):
        obs = env.step(np.array([0.0, 0.5]))[0]
    position = env.unwrapped.robot.state().position
    radius = env.unwrapped.robot.config.footprint_radius
    assert 0.3 < obs["velocity"][1] <= 1.0 and math.dist(position[:2], (-3.0, 0.0)) < radius
    env.close()


@pytest.mark.parametrize("fidelity", ["primitive", "convex"])
def test_fcl_and_pybullet_agree_on_the_huskys_clearance(fidelity):
    """At 150 seeded poses with clearance in (0, 0.5) m, FCL's clearance and pybullet's closest points differ by
    at most 1 mm (measured 0.6 mm: pybullet's cylinders are 64-gon prisms, 0.5 mm inside the true ones)."""
    env = gym.make("ClutterNav-v1", robot="husky", collision_fidelity=fidelity)
    u = env.unwrapped
    rng = np.random.default_rng(0)
    gaps = []
    for i in range(400):
        if i % 40 == 0:
            env.reset(seed=i)
        u.robot.reset_pose(*rng.uniform(-2.5, 2.5, 2), rng.uniform(-math.pi, math.pi))
        report = u.checker.check(u.robot.state(), u.sim.contact_distances(u.robot.body))
        points = [c[8] for body in u.checker._obstacle_bodies
                  for c in pb.getClosestPoints(u.robot.body, body, 0.5, physicsClientId=u.sim.client_id)]
        if points and 0.0 < report.min_clearance < 0.5:
            gaps.append(report.min_clearance - min(points))
    env.close()
    assert len(gaps) > 100
    assert np.max(np.abs(gaps)) < 1e-3


def test_the_huskys_lidar_reads_a_box_ahead_at_its_true_range():
    """Mounted at the front bumper (0.5 m ahead of the base, 0.345 m up), below the clutter's 0.5 m tops: a box face
    2.0 m ahead of the base reads 1.5 m on the forward beam (a scan from the top plate would pass over it)."""
    env = gym.make("ClutterNav-v1", robot="husky")
    box = {"shape": "box", "size": [0.2, 1.0, 0.5], "position": [2.1, 0.0]}
    _, info = env.reset(seed=0, options={"scene": {"obstacles": [box], "start": [0.0, 0.0, 0.0], "goal": [-2.0, 0.0]}})
    lidar = env.unwrapped.sensors[0]
    forward = int(np.argmin(np.abs(lidar.config.angles)))
    assert lidar.config.angles[forward] == 0.0
    assert info["lidar_ranges"][forward] == pytest.approx(1.5, abs=1e-6)
    env.close()
