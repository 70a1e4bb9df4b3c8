"""What the URDF reader refuses (``urdf/checks.py``): URDFs that are not trees, numbers that are not
finite, negative masses, xacro left unexpanded, meshes too large to make; and what a spec's URDF must weigh.

The cases that crashed the interpreter before the checks (a link with two parents segfaulted pybullet's loadURDF, a
NaN mass segfaulted FCL at the first step) or ran away (a kinematic cycle filled memory) run in a child process with
a timeout and a cap on its address space, which also reports its peak memory."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import trimesh

from clutter_gym.assets import asset_path
from clutter_gym.robots.multirotor_model import multirotor_from_spec
from clutter_gym.robots.wheeled import wheeled_base_from_spec
from clutter_gym.urdf import geometry as urdf_geometry
from clutter_gym.urdf.geometry import load_collision_elements, parse_urdf
from clutter_gym.urdf.kinematics import UrdfKinematics

DIFFBOT = asset_path("robots/diffbot.urdf")
HEXAROTOR = Path(__file__).parent / "data" / "hexarotor.urdf"
BASE = {"kind": "diff_drive", "left_wheels": ["left_wheel_joint"], "right_wheels": ["right_wheel_joint"]}
#: the child's address-space cap: the env's children peak at about 0.65 GB of address space, 0.3 GB resident
ADDRESS_SPACE = 3 << 30


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # prepared URDFs land here, not in ~/.cache


def variant(tmp_path: Path, old: str, new: str, source: Path = DIFFBOT, name: str = "v.urdf") -> Path:
    """``source`` with ``old`` (which it must hold) replaced by ``new``, written into ``tmp_path``."""
    text = source.read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new))
    return path


def in_a_child(code: str, timeout: float = 120.0) -> dict:
    """Run ``code`` (which may use ``spec(urdf)``, a diffbot-wheeled spec) in a child process capped at
    :data:`ADDRESS_SPACE`; what it printed last as JSON, with ``refused`` (the ValueError's message, or None) and
    ``peak_mb`` (its resident peak, its own: not the parent's at the fork, which ``ru_maxrss`` carries over) added. A
    crash, a runaway or a hang fails the test."""
    child = textwrap.dedent("""
        import json, resource, sys
        resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
        import gymnasium as gym, numpy as np
        import clutter_gym
        def spec(urdf):
            return {{**{base}, "urdf": urdf}}
        out = {{"refused": None}}
        try:
        {code}
        except ValueError as error:
            out["refused"] = str(error)
        # the resident peak of this process's own memory (VmHWM): ru_maxrss also counts the parent's at the fork
        hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")]
        out["peak_mb"] = (int(hwm[0].split()[1]) if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) / 1024
        print(json.dumps(out))
    """).format(cap=ADDRESS_SPACE, base=json.dumps(BASE), code=textwrap.indent(textwrap.dedent(code), "    "))
    result = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, timeout=timeout,
                            env=os.environ)
    assert result.returncode == 0, f"the child died with {result.returncode}: {result.stderr[-2000:]}"
    return json.loads(result.stdout.strip().splitlines()[-1])


# -- crashes and hangs: each in a child process ---------------------------------------------------------------

def test_a_link_with_two_parent_joints_is_refused_before_pybullet_loads_it(tmp_path):
    """Before: pybullet's loadURDF segfaulted on it, and the reader listed the link twice."""
    urdf = variant(tmp_path, "</robot>", '<joint name="extra" type="fixed"><parent link="base_link"/>'
                                         '<child link="imu_link"/></joint></robot>')
    out = in_a_child(f"""
        env = gym.make("ClutterNav-v1", robot=spec({str(urdf)!r}))
        env.reset(seed=0)
    """)
    assert re.fullmatch(r"robot: the URDF was refused: .*v.urdf: link 'imu_link' is the child of two joints, "
                        r"'imu_joint' and 'extra'; a URDF is a tree: each link hangs from one joint", out["refused"])
    assert out["peak_mb"] < 1024


def test_a_kinematic_cycle_is_refused_not_walked_forever(tmp_path):
    """Before: the kinematics' breadth-first walk went round the cycle until memory ran out (3 GB in 37 s)."""
    urdf = variant(tmp_path, "</robot>", '<link name="a"/><link name="b"/>'
                   '<joint name="to_a" type="fixed"><parent link="base_link"/><child link="a"/></joint>'
                   '<joint name="a_b" type="fixed"><parent link="a"/><child link="b"/></joint>'
                   '<joint name="b_a" type="fixed"><parent link="b"/><child link="a"/></joint></robot>')
    out = in_a_child(f"""
        from clutter_gym.urdf.kinematics import UrdfKinematics
        UrdfKinematics({str(urdf)!r})
    """, timeout=60.0)
    assert re.fullmatch(r".*v.urdf: link 'a' is the child of two joints, 'to_a' and 'b_a'.*", out["refused"])
    assert out["peak_mb"] < 1024


def test_a_nan_mass_is_refused_before_the_first_step(tmp_path):
    """Before: the base's NaN mass passed, and the first step segfaulted in FCL."""
    urdf = variant(tmp_path, '<mass value="2.5"/>', '<mass value="nan"/>')
    out = in_a_child(f"""
        env = gym.make("ClutterNav-v1", robot=spec({str(urdf)!r}))
        env.reset(seed=0)
        for _ in range(5):
            env.step(np.array([1.0, 0.0], dtype=np.float32))
    """)
    assert out["refused"].endswith("v.urdf: link 'base_link' <mass> value: expected 1 finite number, got 'nan'")


# -- a tree of named links and joints ---------------------------------------------------------------------------

@pytest.mark.parametrize("old, new, message", [
    ('<link name="imu_link">', "<link>", r"<link> number 7 has no name; every link needs a unique name"),
    ('<child link="imu_link"/>', '<child link="imu"/>',
     r"joint 'imu_joint' names child link 'imu', which is not a <link> of the URDF"),
    ('<parent link="base_link"/><child link="imu_link"/>', '<child link="imu_link"/>',
     r"joint 'imu_joint' has no <parent link=...>"),
    ('<link name="imu_link">', '<link name="lidar_link">', r"two links are named 'lidar_link'; link names must be "
                                                          r"unique"),
    ('<joint name="imu_joint"', '<joint name="lidar_joint"', r"two joints are named 'lidar_joint'"),
    ("</robot>", '<link name="loose"/></robot>', r"2 links hang from no joint \('base_link', 'loose'\); a URDF has "
                                                 r"one root link: join the others to it"),
    ('<parent link="base_link"/><child link="imu_link"/>', '<parent link="imu_link"/><child link="imu_link"/>',
     r"joint 'imu_joint' joins link 'imu_link' to itself"),
])
def test_what_is_not_a_tree_is_refused_naming_the_link_or_joint(tmp_path, old, new, message):
    """Before: a link without a name or a joint to a missing link gave a KeyError or "expected one root link";
    duplicate names and loose links went to pybullet."""
    urdf = variant(tmp_path, old, new)
    with pytest.raises(ValueError, match=rf"^{re.escape(str(urdf))}: {message}"):
        UrdfKinematics(urdf)


def test_a_cycle_without_a_root_is_named_as_one(tmp_path):
    urdf = variant(tmp_path, "</robot>", '<joint name="back" type="fixed"><parent link="imu_link"/>'
                                         '<child link="base_link"/></joint></robot>')
    with pytest.raises(ValueError, match=r"joints 'back', 'imu_joint' form a kinematic cycle and leave no root "
                                         r"link; a URDF is a tree"):
        parse_urdf(urdf)


# -- numbers, masses and xacro ----------------------------------------------------------------------------------

@pytest.mark.parametrize("old, new, message", [
    ('<origin xyz="-0.0125 0 0"/>\n      <mass', '<origin xyz="nan 0 0"/>\n      <mass',
     r"link 'camera_link' <origin> xyz: expected 3 finite numbers, got 'nan 0 0'"),
    ('ixx="0.02106"', 'ixx="inf"', r"link 'base_link' <inertia> ixx: expected 1 finite number, got 'inf'"),
    ('<limit effort="1.5" velocity="20.0"/>', '<limit effort="1.5" velocity="1e999"/>',
     r"joint 'left_wheel_joint' <limit> velocity: expected 1 finite number, got '1e999'"),
    ('<geometry><box size="0.025 0.09 0.025"/></geometry>', '<geometry><box size="0.025 nan 0.025"/></geometry>',
     r"link 'camera_link' <box> size: expected 3 finite numbers"),
    ('<lateral_friction value="1.0"/>', '<lateral_friction value="NaN"/>', r"link 'left_wheel' <lateral_friction> "
                                                                          r"value: expected 1 finite number"),
    ('<mass value="2.5"/>', '<mass value="2_500"/>', r"link 'base_link' <mass> value: expected 1 finite number, "
                                                     r"got '2_500'"),
    ('<mass value="2.5"/>', '<mass value="-2.5"/>', r"link 'base_link' <mass> value='-2.5' is negative"),
    ('izz="0.036125"', 'izz="-0.036125"', r"link 'base_link' <inertia> izz='-0.036125' is negative"),
    ('<mass value="2.5"/>', '<mass value="$(arg mass)"/>',
     r"link 'base_link' <mass> value='\$\(arg mass\)' holds the unexpanded xacro '\$\(arg mass\)' \(pybullet "
     r"would read it as 0\): expand the file with xacro first"),
    ('<origin xyz="0 0.145 0"/>', '<origin xyz="0 ${track/2} 0"/>',
     r"joint 'left_wheel_joint' <origin> xyz='0 \$\{track/2\} 0' holds the unexpanded xacro '\$\{track/2\}'"),
    ('<mass value="2.5"/>', "", r"link 'base_link' <inertial> needs <mass value=...> and <inertia ...>"),
])
def test_a_number_that_is_not_finite_a_negative_mass_or_leftover_xacro_is_refused(tmp_path, old, new, message):
    """Before: only the multirotor's reader looked at masses; a $(arg ...) left by xacro reached pybullet, which
    read it as 0 (a base that stays put), and a negative mass fell through the floor."""
    urdf = variant(tmp_path, old, new)
    with pytest.raises(ValueError, match=rf"^{re.escape(str(urdf))}: {message}"):
        parse_urdf(urdf)
    with pytest.raises(ValueError, match="the URDF was refused"):
        wheeled_base_from_spec({**BASE, "urdf": str(urdf)}, "spec")


def test_xacro_elements_and_optenv_defaults(tmp_path):
    """A xacro macro left in the file is refused; an ``optenv`` takes its default (pybullet_data's Husky keeps
    some), never the environment's value."""
    macro = variant(tmp_path, '<robot name="diffbot">', '<robot name="diffbot" '
                    'xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:property name="r" value="0.05"/>')
    with pytest.raises(ValueError, match=r"v.urdf: xacro:property 'r' <xacro:property> is xacro, not URDF: expand "
                                         r"the file with xacro first"):
        parse_urdf(macro)
    optenv = variant(tmp_path, '<origin xyz="0.165 0 0.10"/>', '<origin xyz="$(optenv CAMERA_XYZ 0.2 0 0.1)"/>',
                     name="o.urdf")
    os.environ["CAMERA_XYZ"] = "nan nan nan"
    try:
        joint = next(j for j in parse_urdf(optenv).findall("joint") if j.get("name") == "camera_joint")
    finally:
        del os.environ["CAMERA_XYZ"]
    assert joint.find("origin").get("xyz") == "0.2 0 0.1"


def test_every_urdf_of_the_registered_robots_passes():
    for urdf in (DIFFBOT, asset_path("robots/quadrotor.urdf"), HEXAROTOR):
        parse_urdf(urdf)
    for name, kind in (("husky", "diff_drive"), ("kuka_iiwa", "arm"), ("xarm6", "arm")):
        from clutter_gym.robots.registry import resolve_robot
        assert resolve_robot(name, kind, "test") is not None


def test_a_multirotor_without_inertials_is_told_it_has_none(tmp_path):
    """Before: the prepared copy's token grams (1 g a link) flew it as a 7 g airframe."""
    urdf = tmp_path / "bare.urdf"
    urdf.write_text(re.sub(r"<inertial>.*?</inertial>", "", HEXAROTOR.read_text(), flags=re.S))
    spec = {"kind": "multirotor", "urdf": str(urdf), "rotor_links": [f"rotor_{i}" for i in range(1, 7)],
            "spin": [1, -1, 1, -1, 1, -1], "thrust_coefficient": 2.8816e-8, "torque_coefficient": 1.7187e-10,
            "max_rotor_speed": 2272.7, "mounts": {"imu": {"parent": "base_link"}, "sensor_mount": {"parent":
                                                                                                   "base_link"}}}
    with pytest.raises(ValueError, match=r"spec: the URDF was refused: .*bare.urdf has no <inertial> element, so "
                                         r"the robot's mass and inertia are unknown"):
        multirotor_from_spec(spec, "spec")
    zero = tmp_path / "zero.urdf"
    zero.write_text(re.sub(r'<mass value="[^"]*"/>', '<mass value="0"/>', HEXAROTOR.read_text()))
    with pytest.raises(ValueError, match=r"zero.urdf gives its links 0 kg in all"):
        multirotor_from_spec({**spec, "urdf": str(zero)}, "spec")


# -- meshes ------------------------------------------------------------------------------------------------------

def _with_mesh(tmp_path: Path, mesh: Path) -> Path:
    return variant(tmp_path, "</robot>", f'<link name="deco"><collision><geometry><mesh filename="{mesh}"/>'
                   '</geometry></collision></link><joint name="deco_joint" type="fixed"><parent link="base_link"/>'
                   '<child link="deco"/><origin xyz="0 0 0.2"/></joint></robot>', name="deco.urdf")


def test_a_collision_mesh_over_the_face_limit_is_refused_at_once(tmp_path):
    """Before: a 1.3M-triangle mesh took 65 s and 3.6 GB a make; a 328k one 81 s and 1 GB (docs/robots.md). A
    binary STL is counted from its header, so the refusal reads none of its triangles."""
    mesh = tmp_path / "ball.stl"
    trimesh.creation.icosphere(subdivisions=7, radius=0.05).export(mesh)  # 327,680 triangles
    out = in_a_child(f"""
        import time
        start = time.perf_counter()
        try:
            gym.make("ClutterNav-v1", robot=spec({str(_with_mesh(tmp_path, mesh))!r}))
        finally:
            out["seconds"] = time.perf_counter() - start
    """)
    assert re.fullmatch(r"robot: the URDF was refused: deco.urdf link 'deco' collision 0: cannot read mesh .*ball.stl:"
                        r" mesh .*ball.stl has 327,680 triangles, more than the 100,000 a collision mesh may have: "
                        r"simplify it .*", out["refused"])
    assert out["seconds"] < 10.0 and out["peak_mb"] < 1024


def test_the_face_limit_holds_for_every_mesh_format(tmp_path, monkeypatch):
    """Other formats than binary STL are counted on a read without processing (here with the limit lowered so a
    small mesh is over it)."""
    monkeypatch.setattr(urdf_geometry, "MAX_FACES", 1000)
    mesh = tmp_path / "ball.obj"
    trimesh.creation.icosphere(subdivisions=3, radius=0.05).export(mesh)  # 1,280 triangles
    with pytest.raises(ValueError, match=r"has 1,280 triangles, more than the 1,000"):
        load_collision_elements(_with_mesh(tmp_path, mesh))


def test_a_mesh_under_the_limit_is_read_as_before(tmp_path):
    mesh = tmp_path / "ball.stl"
    trimesh.creation.icosphere(subdivisions=2, radius=0.05).export(mesh)
    element = [e for e in load_collision_elements(_with_mesh(tmp_path, mesh)) if e.link == "deco"][0]
    assert len(element.mesh.faces) == 320 and np.allclose(element.size, 0.1, atol=1e-3)


# -- sizes that would make a make run for hours or overflow the stack -----------------------------------------

def test_a_urdf_of_too_many_links_is_refused_at_once(tmp_path):
    """Before: a make's time grew with the square of the links with collision geometry (the allowed-collision matrix
    samples every pair: 110 links added to the diffbot took 110 s), and this file of 2,000 (0.3 MB) ran the child
    out of its 3 GB of address space within half a minute."""
    links = "".join(f'<link name="l{i}"><collision><geometry><sphere radius="0.002"/></geometry></collision></link>'
                    f'<joint name="j{i}" type="fixed"><parent link="base_link"/><child link="l{i}"/>'
                    f'<origin xyz="{0.005 * (i % 40)} {0.005 * (i // 40)} 0.1"/></joint>\n' for i in range(2000))
    urdf = variant(tmp_path, "</robot>", links + "</robot>")
    out = in_a_child(f"""gym.make("ClutterNav-v1", robot=spec({str(urdf)!r}))""", timeout=60.0)
    assert out["refused"].endswith("v.urdf: has 2009 links; a URDF here has 1 to 128") and out["peak_mb"] < 1024


def test_elements_nested_deeper_than_a_urdf_are_refused(tmp_path):
    """Before: 50,000 nested elements (300 kB) gave a raw RecursionError from the XML writer of the prepared copy."""
    urdf = variant(tmp_path, '<link name="imu_link">', '<link name="imu_link">' + "<x>" * 50_000 + "</x>" * 50_000)
    with pytest.raises(ValueError, match=r"the URDF was refused: .*v.urdf: link 'imu_link': elements nested more "
                                         r"than 32 deep"):
        wheeled_base_from_spec({**BASE, "urdf": str(urdf)}, "spec")
