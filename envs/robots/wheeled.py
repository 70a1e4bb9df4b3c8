"""What the env needs to know of a wheeled base's URDF, and how it is read from a robot spec.

A base of kind ``diff_drive`` drives its left and right wheels at the speeds of the unicycle model (one joint a
side for a differential drive, two or more for a skid-steer base such as the Husky). Everything the env needs beyond
the wheel joints is read from the URDF unless the spec gives it: the wheel radius (the wheel link's collision
cylinder), the track (the wheel joints' lateral spread), the footprint radius (the circle about the base origin
that encloses every collision element seen from above, at the wheels' zero angles) and the base frame's height
above the floor (the wheel radius less the axle's height in the base frame). Sensors sit on links named
``lidar_link``, ``imu_link`` and ``camera_link``; a spec's ``mounts`` adds them where the URDF has none
(``robots/urdf_prep.py``). docs/robots.md shows a spec.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.assets import asset_path
from clutter_gym.robots.spec_reading import check_keys, joint_names, load_spec_urdf, number, spec_mounts
from clutter_gym.robots.wheel_checks import check_wheel_geometry, check_wheel_joints, check_wheel_links
from clutter_gym.urdf.geometry import CollisionElement
from clutter_gym.util.transforms import quat_to_matrix

#: The links the sensors sit on.
SENSOR_LINKS = ("lidar_link", "imu_link", "camera_link")
#: The keys of a ``diff_drive`` spec (besides ``kind``); the first three are required.
SPEC_KEYS = ("urdf", "left_wheels", "right_wheels", "name", "wheel_radius", "wheel_separation", "footprint_radius",
             "max_wheel_torque", "mounts")


@dataclass(frozen=True)
class WheeledBase:
    """A wheeled base's URDF and the facts about it the env uses.

    Attributes:
        name: the robot's name (a registered name, or the spec's).
        urdf: the URDF file pybullet and the collision layer load.
        base_link: the URDF's root link: pybullet's base, the frame of the robot's pose.
        left_wheels: joint names of the left wheels; right_wheels: of the right wheels.
        wheel_radius: metres. wheel_separation: the track between the left and right wheel contacts, metres.
        footprint_radius: the radius of the circle about the base origin that encloses the robot from above, metres.
        base_height: height of the base frame above the floor when the robot stands on its wheels, metres.
        focus_height: height above the base frame of the point the ``rgb_array`` view rings, metres.
        tracked_links: links read every step: every link with collision geometry, and the sensor links.
        max_wheel_torque: the wheel motors' torque limit, N m.
    """

    name: str
    urdf: Path
    base_link: str
    left_wheels: tuple[str, ...]
    right_wheels: tuple[str, ...]
    wheel_radius: float
    wheel_separation: float
    footprint_radius: float
    base_height: float
    focus_height: float
    tracked_links: tuple[str, ...]
    max_wheel_torque: float


def diffbot() -> WheeledBase:
    """The TurtleBot-sized differential drive (``assets/robots/diffbot.urdf``) every ClutterNav result so far was
    measured with."""
    return WheeledBase(
        name="diffbot", urdf=asset_path("robots/diffbot.urdf"), base_link="base_link",
        left_wheels=("left_wheel_joint",), right_wheels=("right_wheel_joint",), wheel_radius=0.05,
        wheel_separation=0.29, footprint_radius=0.17, base_height=0.05, focus_height=0.025,
        tracked_links=("left_wheel", "right_wheel", "front_caster", "rear_caster", "imu_link", "lidar_link"),
        max_wheel_torque=1.5,
    )


def wheeled_base_from_spec(spec: Mapping[str, object], where: str, folder: Path | None = None) -> WheeledBase:
    """The base a ``diff_drive`` spec describes (keys :data:`SPEC_KEYS`); ``urdf`` relative to ``folder``.

    Raises:
        ValueError: a key is missing, unknown or out of range, or names a joint or link the URDF does not have, or
            the base does not fit the wheel convention or cannot drive as the unicycle model says
            (``robots/wheel_checks.py``); the message names the key, the URDF and what the URDF offers.
    """
    check_keys(spec, SPEC_KEYS, 3, "diff_drive", where)
    urdf = load_spec_urdf(spec, where, folder, spec_mounts(spec, where))
    kinematics, elements, source = urdf.kinematics, urdf.elements, urdf.source
    sides = {side: joint_names(spec, side, urdf, where) for side in ("left_wheels", "right_wheels")}
    moving = [j.name for j in kinematics.joints]
    links = set(kinematics.links)
    absent = [link for link in SENSOR_LINKS if link not in links]
    if "lidar_link" in absent or "imu_link" in absent:
        raise ValueError(f"{where}: {source} has no {absent}; add them with mounts, e.g. mounts: {{lidar_link: "
                         f"{{parent: {kinematics.root}, xyz: [0, 0, 0.3]}}}} (its links: {kinematics.links})")
    check_wheel_joints(kinematics, sides, urdf.urdf, source, where)
    child = {j.name: j.child for j in kinematics.joints}
    wheel_links = [child[j] for j in (*sides["left_wheels"], *sides["right_wheels"])]
    check_wheel_links(urdf.masses, elements, kinematics.root, wheel_links, source, where)
    frames = kinematics.forward(np.zeros((1, len(moving))))
    radius = number(spec, "wheel_radius", where, _wheel_radius(elements, wheel_links), 0.005, 2.0,
                    derived=f"the wheel links' collision cylinders in {source}")
    check_wheel_geometry(kinematics, elements, wheel_links, radius, "wheel_radius" in spec, source, where)
    lateral = [frames[link][0, 1, 3] for link in wheel_links]
    left, right = lateral[:len(sides["left_wheels"])], lateral[len(sides["left_wheels"]):]
    track = number(spec, "wheel_separation", where, float(np.mean(left) - np.mean(right)), 0.01, 5.0,
                   derived=f"the wheel joints' positions in {source} (the left wheels' mean y less the right's)")
    axle = float(np.mean([frames[link][0, 2, 3] for link in wheel_links]))
    geometric = sorted({e.link for e in elements} - {kinematics.root}, key=kinematics.links.index)
    footprint = number(spec, "footprint_radius", where, footprint_radius(elements, frames), 0.01, 5.0,
                       derived=f"the collision shapes of {source} seen from above")
    return WheeledBase(
        name=urdf.name, urdf=urdf.urdf, base_link=kinematics.root, left_wheels=sides["left_wheels"],
        right_wheels=sides["right_wheels"], wheel_radius=radius, wheel_separation=track, footprint_radius=footprint,
        base_height=radius - axle, focus_height=axle,
        tracked_links=(*geometric, *(link for link in SENSOR_LINKS if link in links and link not in geometric)),
        max_wheel_torque=number(spec, "max_wheel_torque", where, 10.0, 0.01, 500.0),
    )


def _wheel_radius(elements: list[CollisionElement], wheel_links: list[str]) -> float:
    cylinders = [e.size[0] for e in elements if e.link in wheel_links and e.kind == "cylinder"]
    return max(cylinders) if cylinders else math.nan  # nan: number() then asks for wheel_radius in the spec


def footprint_radius(elements: list[CollisionElement], frames: dict[str, np.ndarray], samples: int = 256) -> float:
    """The radius about the base origin, seen from above, that encloses every collision element (boxes by their
    corners, cylinders by ``samples`` points on each rim scaled out to the circle they are inscribed in, spheres and
    capsules by their balls, meshes by their vertices)."""
    reach = 0.0
    angles = np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False)
    for e in elements:
        frame = frames[e.link][0] @ _pose(e)
        if e.kind == "box":
            half = 0.5 * np.array(e.size)
            points = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
        elif e.kind == "cylinder":
            r, length = e.size
            rim = np.stack([r * np.cos(angles), r * np.sin(angles), np.zeros(samples)], axis=1) / math.cos(
                math.pi / samples)
            points = np.concatenate([rim + [0, 0, 0.5 * length], rim - [0, 0, 0.5 * length]])
        elif e.kind in ("sphere", "capsule"):
            r = e.size[0]
            half_length = 0.5 * e.size[1] if e.kind == "capsule" else 0.0
            ends = frame[:3, :3] @ np.array([[0, 0, half_length], [0, 0, -half_length]]).T + frame[:3, 3:4]
            reach = max(reach, float(np.max(np.hypot(ends[0], ends[1]))) + r)
            continue
        else:
            points = np.asarray(e.mesh.vertices)
        world = points @ frame[:3, :3].T + frame[:3, 3]
        reach = max(reach, float(np.max(np.hypot(world[:, 0], world[:, 1]))))
    return reach if reach > 0.0 else math.nan


def _pose(e: CollisionElement) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = quat_to_matrix(e.quaternion)
    out[:3, 3] = e.position
    return out
