"""Robots by name: each env takes ``robot=`` a registered name, a spec mapping, or the path of a YAML spec file.

A robot has a kind, and a task takes the kinds it can drive: ClutterNav-v1 a ground base (:data:`GROUND_KINDS`: a
wheeled base, ``diff_drive``, or an omnidirectional one, ``omni``), ClutterReach-v1 a fixed-base arm (``arm``),
ClutterFly-v1 a multirotor (``multirotor``). A ground kind's entry in :data:`GROUND_ROBOTS` makes the ready robot
from what its reader gives and the env's drive limits, so ClutterNav knows no kind's model. Registering a robot of a
known kind takes a name and a spec (or a function that makes the robot's model); a user's robot of a known kind
needs no Python at all: ``robot={"kind": "diff_drive", "urdf": ..., ...}`` or ``robot="my_robot.yaml"``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from clutter_gym.robots.arm import Arm
from clutter_gym.robots.arm_model import arm_from_spec
from clutter_gym.robots.diffdrive import DiffDriveConfig, DiffDriveRobot
from clutter_gym.robots.multirotor import Multirotor
from clutter_gym.robots.multirotor_model import multirotor_from_spec
from clutter_gym.robots.omni import OmniBase, OmniConfig, omni_from_spec, omnibot
from clutter_gym.robots.panda import PandaArm
from clutter_gym.robots.quadrotor import Quadrotor
from clutter_gym.robots.spec_reading import read_spec_file
from clutter_gym.robots.wheeled import diffbot, wheeled_base_from_spec
from clutter_gym.sim import pybullet_data_file
from clutter_gym.util.checks import short_repr

#: What each kind is, in words, for error messages.
KINDS = {"diff_drive": "wheeled base", "omni": "omnidirectional base", "arm": "fixed-base arm",
         "multirotor": "multirotor"}
#: The reader of each kind's specs (a mapping or a YAML file): what it gives is what the kind's env builds its robot
#: from.
SPEC_READERS: dict[str, Callable[[Mapping[str, Any], str, Path | None], Any]] = {
    "diff_drive": wheeled_base_from_spec,
    "omni": omni_from_spec,
    "arm": lambda spec, where, folder: functools.partial(Arm, arm_from_spec(spec, where, folder)),
    "multirotor": lambda spec, where, folder: functools.partial(Multirotor, multirotor_from_spec(spec, where, folder)),
}


#: The ground kinds (ClutterNav-v1's), each with the robot it makes from its model and the env's (max linear speed
#: m/s, max angular speed rad/s).
GROUND_ROBOTS: dict[str, Callable[[Any, float, float], Any]] = {
    "diff_drive": lambda model, v, w: DiffDriveRobot(DiffDriveConfig(max_linear_speed=v, max_angular_speed=w), model),
    "omni": lambda model, v, w: OmniBase(OmniConfig(max_linear_speed=v, max_angular_speed=w), model),
}
GROUND_KINDS = tuple(GROUND_ROBOTS)


@dataclass(frozen=True)
class RobotEntry:
    """A registered robot: its ``kind`` and ``make()``, which gives what the kind's env builds the robot from."""

    kind: str
    make: Callable[[], Any]


_ROBOTS: dict[str, RobotEntry] = {}


def register_robot(name: str, kind: str, make: Callable[[], Any] | Mapping[str, Any]) -> None:
    """Register ``name`` as a robot of ``kind``: ``make`` is a spec mapping, or a function that returns what the
    kind's env builds its robot from (what :data:`SPEC_READERS` gives).

    Raises:
        ValueError: the name is taken or the kind unknown.
    """
    if kind not in KINDS:
        raise ValueError(f"robot kind must be one of {list(KINDS)}, got {kind!r}")
    if name in _ROBOTS:
        raise ValueError(f"a robot named {name!r} is already registered (a {KINDS[_ROBOTS[name].kind]})")
    if isinstance(make, Mapping):
        spec = dict(make)
        make = lambda: SPEC_READERS[kind](spec, f"robot {name!r}", None)  # noqa: E731  (read on first use)
    _ROBOTS[name] = RobotEntry(kind, make)


def registered(kind: str | None = None) -> list[str]:
    """The registered robot names (of ``kind``), in registration order."""
    return [name for name, entry in _ROBOTS.items() if kind is None or entry.kind == kind]


def resolve_robot(robot: str | Path | Mapping[str, Any], kind: str, env_id: str) -> Any:
    """What ``robot`` (a registered name, a spec mapping, or a YAML spec file's path) describes, as the model of
    ``kind`` the env ``env_id`` builds its robot from.

    Raises:
        ValueError: an unknown name, a robot of another kind, or a bad spec; the message lists the registered robots
            the env takes.
    """
    return _resolve(robot, (kind,), env_id)[1]


def ground_robot(robot: str | Path | Mapping[str, Any], env_id: str, max_linear_speed: float,
                 max_angular_speed: float) -> Any:
    """The ready ground robot ``robot`` describes (of a kind in :data:`GROUND_KINDS`), with the env's drive limits.

    Raises:
        ValueError: as :func:`resolve_robot`.
    """
    kind, model = _resolve(robot, GROUND_KINDS, env_id)
    return GROUND_ROBOTS[kind](model, max_linear_speed, max_angular_speed)


def _resolve(robot: str | Path | Mapping[str, Any], kinds: tuple[str, ...], env_id: str) -> tuple[str, Any]:
    """(kind, model) of ``robot``, one of ``kinds`` (see :func:`resolve_robot`)."""
    names = [name for kind in kinds for name in registered(kind)]
    spec_kinds = " or ".join(repr(kind) for kind in kinds)
    takes = (f"{env_id} takes a {' or '.join(KINDS[kind] for kind in kinds)}: robot= one of {names}, or a spec with "
             f"kind {spec_kinds}")
    where = "robot"
    folder = None
    if isinstance(robot, (str, Path)) and Path(robot).suffix.lower() in (".yaml", ".yml"):
        path = Path(robot).expanduser()
        if not path.is_file():
            raise ValueError(f"robot spec file {str(path)!r} not found; {takes}")
        robot, where, folder = read_spec_file(path), f"robot spec {path}", path.parent
    if isinstance(robot, Mapping):
        spec_kind = robot.get("kind")
        if spec_kind not in kinds:
            raise ValueError(f"{where}: kind {short_repr(spec_kind)} does not fit; {takes}")
        return str(spec_kind), SPEC_READERS[str(spec_kind)](robot, where, folder)
    if isinstance(robot, (str, Path)) and Path(robot).suffix.lower() == ".urdf":
        raise ValueError(f"robot {str(robot)!r} is a URDF: robot= takes its spec, e.g. {{'kind': {kinds[0]!r}, "
                         f"'urdf': {str(robot)!r}, ...}} (docs/robots.md); {takes}")
    if not isinstance(robot, str) or robot not in _ROBOTS:
        raise ValueError(f"unknown robot {short_repr(robot)}; {takes}")
    entry = _ROBOTS[robot]
    if entry.kind not in kinds:
        raise ValueError(f"robot {robot!r} is a {KINDS[entry.kind]}; {takes}")
    return entry.kind, entry.make()


#: Ready poses of the registered arms, rad: joint 1 at zero and the tool point 0.35 m out and 0.45 m up, pointing down
#: (solved on the arm's kinematics, rounded).
READY_IIWA = [0.0, -0.05, 0.0, -2.0, 0.0, 1.19, 0.0]
READY_XARM6 = [0.0, -0.41, -1.22, 0.0, 1.63, 0.0]

register_robot("diffbot", "diff_drive", diffbot)
register_robot("omnibot", "omni", omnibot)
register_robot("panda", "arm", lambda: PandaArm)  # the arm and the flyer: their classes, made with the env's config
register_robot("quadrotor", "multirotor", lambda: Quadrotor)
# Clearpath Husky A200 from pybullet_data: a 44 kg skid-steer base, 1.0 x 0.69 m. The LIDAR sits at the front
# bumper's edge, 0.35 m above the floor (below the generated clutter's 0.5 m tops, which a scan from the top
# plate would pass over), the camera above it; the URDF has its own IMU link.
register_robot("husky", "diff_drive", {
    "urdf": str(pybullet_data_file("husky/husky.urdf")),
    "name": "husky",
    "left_wheels": ["front_left_wheel", "rear_left_wheel"],
    "right_wheels": ["front_right_wheel", "rear_right_wheel"],
    "max_wheel_torque": 20.0,
    "mounts": {"lidar_link": {"parent": "base_link", "xyz": [0.5, 0.0, 0.2]},
               "camera_link": {"parent": "base_link", "xyz": [0.5, 0.0, 0.3]}},
})
# The KUKA LBR iiwa 7 R800 from pybullet_data, with a tool point 0.1 m out from its flange. Its URDF claims 10 rad/s
# and 300 N m on every joint; the limits here are the robot's datasheet values.
register_robot("kuka_iiwa", "arm", {
    "urdf": str(pybullet_data_file("kuka_iiwa/model.urdf")),
    "name": "kuka_iiwa",
    "arm_joints": [f"lbr_iiwa_joint_{i}" for i in range(1, 8)],
    "ee_link": "tool_point",
    "ee_mount": {"parent": "lbr_iiwa_link_7", "xyz": [0.0, 0.0, 0.1]},
    "ready": READY_IIWA,
    "speed_limits": [1.71, 1.71, 1.75, 2.27, 2.44, 3.14, 3.14],
    "effort_limits": [176.0, 176.0, 110.0, 110.0, 110.0, 40.0, 40.0],
    "reach": 0.8,
})
# The UFactory xArm6 from pybullet_data, with a tool point 0.1 m out from its flange; its URDF's limits are kept.
register_robot("xarm6", "arm", {
    "urdf": str(pybullet_data_file("xarm/xarm6_robot.urdf")),
    "name": "xarm6",
    "arm_joints": [f"joint{i}" for i in range(1, 7)],
    "ee_link": "tool_point",
    "ee_mount": {"parent": "link6", "xyz": [0.0, 0.0, 0.1]},
    "ready": READY_XARM6,
    "reach": 0.7,
})
