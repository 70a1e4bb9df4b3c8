"""Multirotors read from specs: a hexarotor from a YAML file (tests/robots/data/) flies in ClutterFly-v1, the quadrotor
written as a spec is the registered one, and bad specs are refused naming the field."""

from __future__ import annotations

import math
import re
from dataclasses import asdict
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

from clutter_gym.robots import Multirotor, MultirotorConfig
from clutter_gym.robots.multirotor_model import multirotor_from_spec
from clutter_gym.robots.quadrotor import quadrotor_model
from clutter_gym.robots.registry import register_robot, registered
from clutter_gym.robots.rigid_body import rigid_body
from clutter_gym.sim import Sim
from clutter_gym.util.quiet import quiet_c_output

with quiet_c_output():
    import pybullet as pb

DATA = Path(__file__).parent / "data"
HEXAROTOR = DATA / "hexarotor.yaml"
HUB_TOP = 0.022  # metres above the base origin: the hexarotor's propeller discs' tops (hubs 20 mm up, 4 mm thick)
SIZE = (4.0, 4.0, 2.0)  # a small volume: cheap path distances
OPEN = {"obstacles": [], "start": [0.0, 0.0, 1.0, 0.0], "goal": [1.5, 1.5, 1.0]}


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # prepared URDFs land here, not in ~/.cache


def hexarotor_spec() -> dict:
    """The shipped hexarotor spec as a mapping, its URDF made absolute."""
    spec = yaml.safe_load(HEXAROTOR.read_text())
    return {**spec, "urdf": str(DATA / spec["urdf"])}


def quadrotor_spec() -> dict:
    """The built-in quadrotor written out as a user's spec: its URDF, rotor links, spins and coefficients."""
    model = asdict(quadrotor_model())
    keys = ("rotor_links", "spin", "thrust_coefficient", "torque_coefficient", "max_rotor_speed", "min_rotor_speed",
            "motor_time_constant", "drag_xy", "drag_z", "rotor_radius")
    return {"kind": "multirotor", "name": "quadrotor", "urdf": str(model["urdf"]),
            **{key: list(model[key]) if isinstance(model[key], tuple) else model[key] for key in keys}}


def rollout(env, steps: int, seed: int) -> list:
    """Each step's observation, reward, flags, cost and clearance under seeded random actions."""
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
        rows.append(({k: v.copy() for k, v in obs.items()}, reward, terminated, truncated, info["cost"],
                     info["min_clearance"]))
        if terminated or truncated:
            obs, _ = env.reset()
    return rows


def assert_same(a: list, b: list) -> None:
    for (obs_a, *rest_a), (obs_b, *rest_b) in zip(a, b, strict=True):
        assert obs_a.keys() == obs_b.keys()
        for key in obs_a:
            np.testing.assert_array_equal(obs_a[key], obs_b[key], err_msg=key)
        assert rest_a == rest_b


# -- the quadrotor as a spec ------------------------------------------------------------------------------------

@pytest.mark.parametrize("settings", [{}, {"aero": ("drag", "ground_effect"), "noise": "harsh",
                                           "observe_thrust_ratio": True, "sensors": ("imu", "lidar")}])
def test_the_quadrotor_written_as_a_spec_flies_the_registered_quadrotors_trajectory(make_env, settings):
    """Same URDF (the spec's prepared copy), rotors and coefficients: the same seeded trajectory bit for bit, clean
    and under every effect the airframe's values reach (drag, ground effect, harsh dynamics, the thrust estimate)."""
    spec_env = make_env("ClutterFly-v1", robot=quadrotor_spec(), **settings)
    model, built_in = spec_env.unwrapped.robot.model, quadrotor_model()
    assert model.urdf != built_in.urdf and set(model.tracked_links) == set(built_in.tracked_links)
    assert_same(rollout(spec_env, 200, seed=4), rollout(make_env("ClutterFly-v1", robot="quadrotor", **settings),
                                                         200, seed=4))


# -- the hexarotor ----------------------------------------------------------------------------------------------

def test_the_hexarotor_is_read_from_its_yaml_file_with_its_urdfs_layout():
    model = multirotor_from_spec(yaml.safe_load(HEXAROTOR.read_text()), "spec", DATA)
    assert model.name == "hexarotor" and len(model.rotor_links) == 6 and model.spin == (1.0, -1.0) * 3
    assert model.rotor_radius == 0.0231  # the rotor links' largest collision cylinder
    assert model.drag_xy == model.drag_z == 0.0 and model.min_rotor_speed == 0.0  # the defaults
    assert model.tracked_links[-2:] == ("imu", "sensor_mount")  # mounted by the spec
    assert {"battery", "arm_1", "rotor_6"} <= set(model.tracked_links) and "base_link" not in model.tracked_links
    assert model.focus_radius == pytest.approx(0.06 + 0.0231, abs=1e-12)


def test_the_hexarotor_holds_a_hover_under_the_rate_control(make_env):
    """The hover action, held for 5 s from a hovering start: thrust and weight balance and the six rotors' shares
    give no torque, to rounding. What moves it: the action reaches the env as float32, so a0 is off by at most
    2^-25 (half a float32 spacing below 1), the collective thrust (a0 + 1) / 2 T_max by 2^-26 T_max, and with
    T_max / m = 2 g / (a0 + 1) the climb is at most 2^-26 2 g / (a0 + 1) t^2 / 2 (3.5 um here). Horizontally
    only float64 rounding acts: the shares' torque left over is about 1e-18 N m against the rate loop's kp J, so
    the tilt stays near 1e-13 rad and the drift near 1e-12 m; the bounds below leave three orders of magnitude."""
    env = make_env("ClutterFly-v1", robot=str(HEXAROTOR), volume_size=SIZE)
    robot = env.unwrapped.robot
    assert env.action_space.shape == (4,) and env.observation_space["rotor_speeds"].shape == (6,)
    env.reset(seed=0, options={"scene": OPEN})
    action = robot.hover_action(env.unwrapped.sim.gravity).astype(np.float32)
    seconds = 5.0
    for _ in range(int(seconds * 30)):
        obs, reward, terminated, truncated, info = env.step(action)
        assert not terminated and info["cost"] == 0.0
    state = robot.state()
    climb_bound = 2.0**-26 * 2.0 * 9.81 / (float(action[0]) + 1.0) * seconds**2 / 2.0
    assert abs(state.position[2] - 1.0) <= climb_bound
    assert np.abs(state.position[:2]).max() < 1e-9
    assert np.linalg.norm(state.rotation[:2, 2]) < 1e-9  # sine of the tilt
    np.testing.assert_allclose(obs["rotor_speeds"], obs["rotor_speeds"][0], rtol=1e-6)  # the shares are equal


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_the_hexarotors_rate_loop_settles_each_axis_as_the_quadrotors_does(axis):
    """The gains scale with the inertia and the motors lag alike, so the linearised loop is the quadrotor's
    (tests/robots/test_quadrotor.py): 4.3 % overshoot, 5 % settling in 0.21 s; the same bounds (10 %, 0.3 s) hold.
    The other two axes stay still: the mixer's pseudo-inverse puts each torque on the right rotors."""
    sim = Sim(physics_hz=240.0)
    try:
        robot = Multirotor(multirotor_from_spec(hexarotor_spec(), "spec"))
        robot.load(sim)
        robot.reset_to((0.0, 0.0, 5.0, 0.0))
        action = robot.hover_action(sim.gravity)
        step = 1.0  # rad/s: no rotor saturates
        action[1 + axis] = step / (3.0, 3.0, 2.0)[axis]  # the default max_roll_rate, max_pitch_rate, max_yaw_rate
        robot.apply_action(action)
        rates = []
        for _ in range(int(0.6 * 240)):
            robot.before_tick()
            sim.step()
            state = robot.state()
            rates.append(state.rotation.T @ np.asarray(state.angular_velocity))
    finally:
        sim.close()
    rates = np.array(rates)
    response = rates[:, axis] / step
    t = np.arange(1, len(rates) + 1) / 240.0
    assert response.max() - 1 < 0.10
    assert t[np.nonzero(np.abs(response - 1) > 0.05)[0][-1] + 1] < 0.3
    assert abs(response[-12:].mean() - 1) < 0.01
    assert np.abs(np.delete(rates, axis, axis=1)).max() < 0.05 * step


def test_the_hexarotor_takes_one_motor_command_per_rotor():
    sim = Sim(physics_hz=240.0)
    try:
        robot = Multirotor(multirotor_from_spec(hexarotor_spec(), "spec"), MultirotorConfig(control="motors"))
        robot.load(sim)
        robot.reset_to((0.0, 0.0, 5.0, 0.0))
        assert robot.action_space.shape == (6,)
        robot.apply_action(robot.hover_action(sim.gravity))
        for _ in range(240):
            robot.before_tick()
            sim.step()
        assert abs(robot.state().position[2] - 5.0) < 1e-6  # the hover speeds, commanded rotor by rotor
        command = robot.hover_action(sim.gravity)
        command[[1, 3, 5]] = 1.0  # the clockwise rotors at full speed: the body yaws counter-clockwise
        robot.apply_action(command)
        for _ in range(24):
            robot.before_tick()
            sim.step()
        assert robot.state().angular_velocity[2] > 0.1
    finally:
        sim.close()


def test_the_hexarotor_passes_gymnasiums_and_sb3s_env_checks(make_env):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = make_env("ClutterFly-v1", robot=hexarotor_spec(), volume_size=SIZE)
    check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)


def test_the_hexarotor_replays_its_seeded_trajectory_in_lockstep(make_env):
    a, b = (make_env("ClutterFly-v1", robot=str(HEXAROTOR), volume_size=SIZE) for _ in range(2))
    first = rollout(a, 90, seed=6)
    assert_same(first, rollout(b, 90, seed=6))
    assert any(row[0]["velocity"][3:].any() for row in first)  # it moved


def test_the_hexarotors_clearance_is_its_shapes_and_a_contact_costs(make_env):
    """FCL measures the hexarotor's own shapes: at the start 1 m up in an open 2 m high volume the nearest face is
    the ceiling, 2 - 1 - 0.022 m from the propeller tops. Flying up into a slab is a contact both engines see."""
    env = make_env("ClutterFly-v1", robot=str(HEXAROTOR), volume_size=SIZE, terminate_on_collision=True)
    u = env.unwrapped
    env.reset(options={"scene": OPEN})
    report = u.checker.check(u.robot.state(), u.sim.contact_distances(u.robot.body))
    assert report.min_clearance == pytest.approx(2.0 - 1.0 - HUB_TOP, abs=1e-9)
    slab = {"shape": "box", "size": [1.0, 1.0, 0.1], "position": [0.0, 0.0], "z": 1.3}
    env.reset(options={"scene": {**OPEN, "obstacles": [slab]}})
    for step in range(60):
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0, 0.0, 0.0]))
        if terminated:
            break
    assert terminated and step > 0 and info["cost"] == 1.0 and info["n_contacts"] > 0
    assert info["pybullet_contacts"] > 0 and not info["contact_disagreement"]
    assert info["closest_pair"][1] == 0  # the slab


def test_fcl_and_pybullet_agree_on_the_hexarotors_clearance(make_env):
    """At seeded level poses in generated volumes with clearance in (0, 0.5) m, FCL's clearance and pybullet's
    closest points differ by at most 1 mm, the band the built-in quadrotor's shapes meet at the same poses (FCL
    reads shorter near the propeller discs and the battery than pybullet's convex distance query does)."""
    env = make_env("ClutterFly-v1", robot=str(HEXAROTOR), obstacle_density=0.15)
    u = env.unwrapped
    rng = np.random.default_rng(0)
    gaps = []
    for i in range(300):
        if i % 60 == 0:
            env.reset(seed=i)
        x, y = rng.uniform(-4.5, 4.5, 2)
        u.robot.reset_to((x, y, rng.uniform(0.2, 3.8), rng.uniform(-math.pi, math.pi)))
        report = u.checker.check(u.robot.state(), u.sim.contact_distances(u.robot.body))
        points = [c[8] for body in u.checker._obstacle_bodies
                  for c in pb.getClosestPoints(u.robot.body, body, 0.5, physicsClientId=u.sim.client_id)]
        if points and 0.0 < report.min_clearance < 0.5:
            gaps.append(report.min_clearance - min(points))
    assert len(gaps) > 50
    assert np.max(np.abs(gaps)) < 1e-3


# -- registered by name ---------------------------------------------------------------------------------------

def test_a_registered_multirotor_spec_is_read_when_an_env_first_asks_for_it(monkeypatch, make_env):
    from clutter_gym.robots import registry

    monkeypatch.setattr(registry, "_ROBOTS", dict(registry._ROBOTS))  # the test's registrations end with it
    register_robot("my_hex", "multirotor", {**hexarotor_spec(), "max_rotor_speed": -1.0})
    assert registered("multirotor") == ["quadrotor", "my_hex"]
    with pytest.raises(ValueError, match=r"robot 'my_hex': max_rotor_speed must be a number in \(0.0, 10000.0\]"):
        make_env("ClutterFly-v1", robot="my_hex")
    register_robot("hex", "multirotor", hexarotor_spec())
    assert make_env("ClutterFly-v1", robot="hex", volume_size=SIZE).unwrapped.robot.name == "hexarotor"


# -- bad specs --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("change, message", [
    ({"rotor_links": ["rotor_1", "rotor_2", "rotor_3", "rotor_4", "rotor_5", "rotor_7"]},
     r"rotor_links names \['rotor_7'\], not links of .*hexarotor.urdf; its links: \['base_link', 'battery'"),
    ({"rotor_links": "rotor_1"}, r"rotor_links must be a list of 3 to 16 distinct link names"),
    ({"rotor_links": ["rotor_1"] * 6}, r"rotor_links must be a list of 3 to 16 distinct link names"),
    ({"spin": [1, -1, 1, -1, 1]}, r"spin must be 6 values, one per rotor_links entry: \+1 for a rotor that turns "
                                  r"counter-clockwise seen from above, -1 for clockwise; got \[1, -1, 1, -1, 1\]"),
    ({"spin": [1, -1, 1, -1, 1, 0]}, r"spin must be 6 values"),
    ({"thrust_coefficient": 0}, r"thrust_coefficient must be a number in \(0.0, 0.0001\], got 0.0"),
    ({"torque_coefficient": -1e-10}, r"torque_coefficient must be a number in \(0.0, 1e-05\]"),
    ({"max_rotor_speed": "fast"}, r"max_rotor_speed must be a number in \(0.0, 10000.0\], got 'fast'"),
    ({"motor_time_constant": 2}, r"motor_time_constant must be a number in \[0.0, 1.0\]"),
    ({"min_rotor_speed": 3000}, r"min_rotor_speed must be in \[0, max_rotor_speed=2272.7\)"),
    ({"spin": [1] * 6}, r"rotor_links \[.*\] with spin \[1.0, 1.0, .*\]: the rotors cannot give collective thrust and "
                        r"roll, pitch and yaw torque independently \(their allocation has rank 3 < 4\): every rotor "
                        r"turns the same way"),
    # a rectangle whose left pair turns counter-clockwise: its yaw torque is a roll torque
    ({"rotor_links": ["rotor_1", "rotor_3", "rotor_4", "rotor_6"], "spin": [1, 1, -1, -1]},
     r"with spin .*: the rotors cannot give .*rank 3 < 4\): the spins' yaw torque comes only with roll or pitch "
     r"torque"),
    ({"rotor_links": ["rotor_1", "rotor_2", "rotor_3"], "spin": [1, -1, 1]},
     r"rank 3 < 4\): 3 rotors give at most 3 of the four; it takes four or more"),
    ({"rotor_links": ["rotor_1", "rotor_2", "rotor_3", "rotor_6"], "spin": [1, -1, 1, -1]},
     r"a level hover needs thrust shares \[.*\], not all positive: the centre of mass must lie within the rotors"),
    ({"max_rotor_speed": 1500}, r"max_rotor_speed 1500.0 rad/s gives at most 0.389 N of collective thrust, which "
                                r"does not lift the airframe's 0.4611 N \(0.047 kg\)"),
    ({"mounts": {}}, r"hexarotor.urdf has no \['imu', 'sensor_mount'\] .*; add them with mounts"),
    ({"mounts": {"imu": {"parent": "base_link"}, "sensor_mount": {"parent": "deck"}}},
     r"no link 'deck' to mount 'sensor_mount' on; its links: \['base_link'"),
    ({"rotors": 6}, r"unknown keys \['rotors'\]; a multirotor spec takes \['urdf', 'rotor_links', 'spin'"),
    ({"urdf": "nowhere.urdf"}, "urdf 'nowhere.urdf' is not a file"),
])
def test_a_bad_spec_is_refused_naming_the_field(change, message):
    with pytest.raises(ValueError, match=message):
        multirotor_from_spec({**hexarotor_spec(), **change}, "spec")


@pytest.mark.parametrize("field", ["urdf", "rotor_links", "spin", "thrust_coefficient", "torque_coefficient",
                                   "max_rotor_speed"])
def test_a_spec_without_a_required_field_is_refused_naming_it(field):
    spec = hexarotor_spec()
    del spec[field]
    with pytest.raises(ValueError, match=f"spec: missing '{field}' \\(a multirotor spec needs \\['urdf'"):
        multirotor_from_spec(spec, "spec")


def edited_urdf(tmp_path: Path, pattern: str, new: str) -> str:
    """The hexarotor's URDF with every match of the regular expression ``pattern`` replaced by ``new``, written into
    ``tmp_path``."""
    text, n = re.subn(pattern, new, (DATA / "hexarotor.urdf").read_text())
    assert n > 0
    path = tmp_path / "edited.urdf"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("pattern, new, message", [
    (r'(<origin xyz="\S+) \S+ (0\.02"/>)', r"\1 0 \2",  # every rotor's y to 0
     r"rotor_links .* with spin .*: the rotors cannot give collective thrust and roll, pitch and yaw torque "
     r"independently \(their allocation has rank 3 < 4\): the rotors lie on one line seen from above"),
    (r'<joint name="rotor_1_joint" type="fixed">', '<joint name="rotor_1_joint" type="revolute">',
     r"has moving joints \['rotor_1_joint'\]; a multirotor's airframe is rigid"),
    (r'<origin xyz="0.051961524227 0.030000000000 0.02"/>',
     '<origin xyz="0.051961524227 0.030000000000 0.02" rpy="0.2 0 0"/>',
     r"rotor_links \['rotor_1'\] of .*edited.urdf are tilted"),
    (r'(<link name="battery">\s*<inertial>)<mass value="0"/>', r'\1<origin xyz="0 0 -0.01"/><mass value="0.002"/>',
     r"pybullet would put the merged airframe's centre of mass at .*: links \['battery'\] carry mass off their "
     r"origins"),
    (r'ixy="0" ixz="0" iyy="3.1e-05"', 'ixy="1e-6" ixz="0" iyy="3.1e-05"',
     r"the airframe's inertia about its centre of mass has products of inertia"),
    (r"</robot>", "<link name='broken'>", r"the URDF was refused: cannot parse URDF"),
])
def test_an_airframe_the_rotors_or_pybullet_cannot_fly_is_refused_naming_why(tmp_path, pattern, new, message):
    with pytest.raises(ValueError, match=message):
        multirotor_from_spec({**hexarotor_spec(), "urdf": edited_urdf(tmp_path, pattern, new)}, "spec")


def test_an_airframe_without_mass_is_refused(tmp_path):
    """Not reachable through a spec, whose mounts weigh 1 g each; a robot's own URDF could weigh nothing."""
    urdf = edited_urdf(tmp_path, r'<mass value="0.045"/>', '<mass value="0"/>')
    with pytest.raises(ValueError, match=r"edited.urdf: its links weigh nothing"):
        rigid_body(urdf)


def test_a_mass_without_its_value_is_refused_when_the_spec_is_read(tmp_path):
    """A mass element without its value: pybullet refuses the file only when the env loads it (the spec reader took
    it as 0 kg until the URDF reader checked it), so the spec reader refuses it, naming the link."""
    urdf = edited_urdf(tmp_path, r'(<link name="battery">\s*<inertial>)<mass value="0"/>', r"\1<mass/>")
    with pytest.raises(ValueError, match=r"the URDF was refused: .*edited.urdf: link 'battery' <inertial> needs "
                                         r"<mass value=\.\.\.> and <inertia \.\.\.>"):
        multirotor_from_spec({**hexarotor_spec(), "urdf": urdf}, "spec")


def test_a_yaml_spec_that_is_not_a_mapping_is_refused(tmp_path):
    spec = tmp_path / "hex.yaml"
    spec.write_text("- kind: multirotor\n")
    with pytest.raises(ValueError, match=r"robot spec .*hex.yaml: expected a mapping of keys, got list"):
        gym.make("ClutterFly-v1", robot=str(spec))
    spec.write_text("kind: diff_drive\n")
    with pytest.raises(ValueError, match=r"kind 'diff_drive' does not fit; ClutterFly-v1 takes a multirotor: robot= "
                                         r"one of \['quadrotor'\], or a spec with kind 'multirotor'"):
        gym.make("ClutterFly-v1", robot=str(spec))


def test_a_spec_hexarotor_gets_the_reduced_flight_model_and_flies_it_as_pybullet_does(make_env):
    """Its reduced model comes from its spec and URDF (six rotors, its mixer's pseudo-inverse): ``"auto"`` takes it,
    and 2 s of seeded commands in the open volume fly as full physics flies them, to a micrometre."""
    runs = []
    for mode in ("physics", "auto"):
        env = make_env("ClutterFly-v1", robot=str(HEXAROTOR), volume_size=SIZE, dynamics=mode)
        _, info = env.reset(seed=0, options={"scene": OPEN})
        assert info["dynamics"]["model"] == ("physics" if mode == "physics" else "reduced")
        hover = env.unwrapped.robot.hover_action(env.unwrapped.sim.gravity)
        for offset in np.random.default_rng(0).uniform(-0.1, 0.1, (60, 4)):
            env.step(hover + offset)
        runs.append(env.unwrapped.dynamics.state().position)
    assert env.unwrapped.dynamics.reduced_steps == 60
    assert np.abs(runs[0] - runs[1]).max() < 1e-6
