"""What the env needs to know of a fixed-base arm's URDF, and how it is read from a robot spec.

An arm of kind ``arm`` is position-controlled joint by joint (``robots/panda.py``). The spec names its joints, the
link whose point must reach the target (or mounts one: a tool point on the flange) and a ready pose; limits come from
the URDF's ``<limit>`` elements unless the spec gives them (pybullet_data's KUKA iiwa claims 10 rad/s a joint).
Everything else the ClutterReach task needs about an arm is here too: where its shoulder is and how far it reaches
(targets are drawn within that ball), and the links read every step. docs/robots.md shows a spec.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.robots.spec_reading import check_keys, joint_names, load_spec_urdf, mount, number, numbers
from clutter_gym.urdf.kinematics import Joint

#: The keys of an ``arm`` spec (besides ``kind``); the first four are required.
SPEC_KEYS = ("urdf", "arm_joints", "ee_link", "ready", "name", "ee_mount", "speed_limits", "effort_limits",
             "reach")


@dataclass(frozen=True, eq=False)
class ArmModel:
    """A fixed-base arm's URDF and the facts about it the env uses.

    Attributes:
        name: the robot's name.
        urdf: the URDF file pybullet and the collision layer load.
        base_link: the URDF's root link, fixed at the world origin.
        arm_joints: the controlled joints, base to tip.
        finger_joints: joints held at ``finger_opening`` (a gripper that never moves), possibly none.
        finger_opening: metres (or radians) each finger joint is held at; finger_range: the fingers' limits.
        ee_link: the link whose origin must reach the target.
        tracked_links: links read every step: every link with collision geometry but the base, and ``ee_link``.
        fixed_links: tracked links bolted to the base (no moving joint between): they touch the table by design.
        ready: joint positions of the ready pose, the end effector pointing down (episodes start around it).
        lower, upper: joint limits, radians. speed_limit: rad/s. effort_limit: N m.
        shoulder: the point (metres, base frame) targets are drawn around; reach: how far from it, metres.
        hand_radius: metres about the end effector the rendered view rings.
    """

    name: str
    urdf: Path
    base_link: str
    arm_joints: tuple[str, ...]
    finger_joints: tuple[str, ...]
    finger_opening: float
    ee_link: str
    tracked_links: tuple[str, ...]
    ready: tuple[float, ...]
    lower: np.ndarray
    upper: np.ndarray
    speed_limit: np.ndarray
    effort_limit: np.ndarray
    shoulder: np.ndarray
    reach: float
    hand_radius: float = 0.08
    finger_range: tuple[float, float] = (0.0, 0.0)
    fixed_links: tuple[str, ...] = ()

    @property
    def ee_row(self) -> int:
        """Row of ``ee_link`` in the state's tracked links."""
        return self.tracked_links.index(self.ee_link)


def arm_from_spec(spec: Mapping[str, object], where: str, folder: Path | None = None) -> ArmModel:
    """The arm an ``arm`` spec describes (keys :data:`SPEC_KEYS`); ``urdf`` relative to ``folder``.

    Raises:
        ValueError: a key is missing, unknown or out of range, or names a joint or link the URDF does not have; the
            message names the key, the URDF and what it offers.
    """
    check_keys(spec, SPEC_KEYS, 4, "arm", where)
    ee_link = str(spec["ee_link"])
    mounts = () if spec.get("ee_mount") is None else (mount(ee_link, spec["ee_mount"], f"{where}: ee_mount"),)
    urdf = load_spec_urdf(spec, where, folder, mounts)
    kinematics, elements, source = urdf.kinematics, urdf.elements, urdf.source
    joints = joint_names(spec, "arm_joints", urdf, where, 3, 9)
    moving = {j.name: j for j in kinematics.joints}
    others = [j for j in moving if j not in joints]
    if others:
        raise ValueError(f"{where}: {source} has moving joints {others} besides arm_joints; an arm spec drives every "
                         "moving joint (grippers are not read from specs yet)")
    if ee_link not in kinematics.links:
        raise ValueError(f"{where}: ee_link {ee_link!r} is not a link of {source}; add it with ee_mount or pick one "
                         f"of {kinematics.links}")
    _check_arm_joints([moving[j] for j in joints], source, where)
    n = len(joints)
    lower = np.array([moving[j].lower for j in joints])
    upper = np.array([moving[j].upper for j in joints])
    ready = np.array(numbers(spec["ready"], n, f"{where}: ready", -2 * math.pi, 2 * math.pi))
    if np.any(ready < lower) or np.any(ready > upper):
        raise ValueError(f"{where}: ready {ready.tolist()} is outside the joint limits {lower.tolist()} .. "
                         f"{upper.tolist()}")
    limits = _urdf_limits(urdf.urdf, joints)
    speed, effort = (np.array(_limits(spec, key, dict(zip(joints, given)), source, where, high))
                     for key, given, high in (("speed_limits", limits[0], 20.0), ("effort_limits", limits[1], 5000.0)))
    geometric = [e.link for e in elements if e.link != kinematics.root]
    tracked = tuple(dict.fromkeys([link for link in kinematics.links if link in geometric] + [ee_link]))
    moved = {j.child for j in kinematics.joints}

    def bolted(link: str) -> bool:  # no moving joint between the link and the root
        while link != kinematics.root:
            if link in moved:
                return False
            link = kinematics.parent[link]
        return True

    if bolted(ee_link):
        what = "the root link" if ee_link == kinematics.root else "bolted to the root link"
        raise ValueError(f"{where}: ee_link {ee_link!r} is {what} of {source}: no arm joint moves it; pick a link "
                         "past the last arm joint (or mount one there with ee_mount)")
    frames = kinematics.forward(np.zeros((1, n)))
    shoulder = frames[moving[joints[1]].child][0, :3, 3]
    reach = number(spec, "reach", where, 0.8, 0.2, 2.0)
    return ArmModel(name=urdf.name, urdf=urdf.urdf, base_link=kinematics.root, arm_joints=joints, finger_joints=(),
                    finger_opening=0.0, ee_link=ee_link, tracked_links=tracked, ready=tuple(float(v) for v in ready),
                    lower=lower, upper=upper, speed_limit=speed, effort_limit=effort,
                    shoulder=np.array([0.0, 0.0, float(shoulder[2])]), reach=reach,
                    fixed_links=tuple(link for link in tracked if bolted(link)))


def _check_arm_joints(joints: Sequence[Joint], source: Path, where: str) -> None:
    """Refuse an arm joint that slides (the arm's joint spaces, its planner and its IK read angles) or whose range
    is empty or inverted (pybullet reads lower > upper as no limit at all)."""
    for joint in joints:
        if joint.kind == "prismatic":
            raise ValueError(f"{where}: arm_joints {joint.name!r} of {source} is prismatic; an arm spec takes "
                             "revolute and continuous joints (a sliding axis is not read from specs yet)")
        if not joint.lower < joint.upper:
            raise ValueError(f"{where}: arm_joints {joint.name!r} of {source} has <limit lower={joint.lower:g} "
                             f"upper={joint.upper:g}> (0 where not given): an arm joint needs lower < upper, in "
                             "radians")


def _limits(spec: Mapping[str, object], key: str, given: Mapping[str, float], source: Path, where: str,
            high: float) -> list[float]:
    """``spec[key]``, or the limits the URDF gives (``given``, nan where it gives none) when the spec leaves it out."""
    if key not in spec:
        missing = [joint for joint, value in given.items() if math.isnan(value)]
        if missing:
            attribute = "velocity" if key == "speed_limits" else "effort"
            raise ValueError(f"{where}: {key} was not given, and {source} gives no <limit {attribute}=...> for "
                             f"{missing}: give {key} in the spec")
        wrong = {joint: value for joint, value in given.items() if not 0.01 <= value <= high}
        if wrong:
            raise ValueError(f"{where}: {key} was not given, and the <limit> of {source} gives {wrong}, outside "
                             f"[0.01, {high:g}]: give {key} in the spec")
    return numbers(spec.get(key, list(given.values())), len(given), f"{where}: {key}", 0.01, high)


def _urdf_limits(urdf: Path, joints: Sequence[str]) -> tuple[list[float], list[float]]:
    """Each joint's ``<limit velocity= effort=>`` (nan where absent: the spec must then give it)."""
    found = {}
    for joint in ET.parse(urdf).getroot().findall("joint"):
        limit = joint.find("limit")
        if limit is not None:
            found[joint.get("name")] = (float(limit.get("velocity", "nan")), float(limit.get("effort", "nan")))
    pairs = [found.get(j, (math.nan, math.nan)) for j in joints]
    return [p[0] for p in pairs], [p[1] for p in pairs]
