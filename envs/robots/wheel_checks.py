"""What a wheeled base's URDF must be for the unicycle model the env drives it by, checked when its spec is read.

The env commands the left wheels at ``(v - w L/2) / r`` and the right ones at ``(v + w L/2) / r`` and reads the base's
forward speed along its +x, so the base must follow the convention of ROS's REP 103: it drives along its +x, its
left wheels sit on +y and its right wheels on -y, and every wheel turns about an axle along +y (a positive wheel speed
rolls it forward). A URDF that does not fit would drive sideways or spin while the env's ``velocity`` reading says it
stands still, so it is refused, in one line naming the likely cause: swapped sides, or a base that drives along
another axis. So is a base that cannot drive as the model says: a wheel that slides or is stopped by its joint
limits, a wheel without collision geometry, a chassis or caster that reaches below the wheels (the base rests on it),
a ``wheel_radius`` far from the wheels' collision shapes, and a base or wheel of zero mass (pybullet holds a base of
zero mass still, and zero-mass wheels do not drive it).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from clutter_gym.urdf.geometry import CollisionElement, parse_urdf
from clutter_gym.urdf.kinematics import UrdfKinematics
from clutter_gym.util.transforms import quat_to_matrix

#: The largest angle between a wheel's axle and the base's +y (a wheel turned further scrubs sideways as it rolls).
AXLE_TOLERANCE = math.radians(5.0)
#: Metres another link's collision shapes may reach below the wheels' lowest points: casters a millimetre or two
#: below the diffbot's wheels cost much or all of a forward drive's travel (docs/robots.md gives the figures).
GROUND_TOLERANCE = 5e-4
#: How far a ``wheel_radius`` may be from the radius the wheel's collision shape gives (reach below its axle), as a
#: share of the latter: the wheel speeds are ``v / r``, so a wrong radius scales every commanded speed; a quarter is
#: beyond tyre compression or a tread's depth, and catches a wrong unit or a wheel that does not stand on its rim.
RADIUS_TOLERANCE = 0.25
#: Radians: a revolute wheel whose limits pybullet enforces (lower <= upper) must span this much to count as free
#: (400 rad/s, the fastest wheel a spec allows, turns 8,000 rad in a 20 s episode).
FREE_SPAN = 1e6


def check_wheel_joints(kinematics: UrdfKinematics, sides: Mapping[str, Sequence[str]], urdf: Path, source: Path,
                       where: str) -> None:
    """Refuse wheel lists that overlap, wheels that slide or are stopped by their limits, and wheels off the
    convention: axles along +y, the left wheels on +y and the right ones on -y (in the base frame, joints at zero).

    Args:
        kinematics: the prepared URDF's. sides: ``left_wheels`` and ``right_wheels``, joint names.
        urdf: the prepared URDF (its joint limits are read as pybullet reads them). source: the user's URDF.
    """
    left, right = sides["left_wheels"], sides["right_wheels"]
    for key, names in sides.items():
        twice = sorted({name for name in names if list(names).count(name) > 1})
        if twice:
            raise ValueError(f"{where}: {key} names {twice} more than once")
    both = [name for name in left if name in right]
    if both:
        raise ValueError(f"{where}: left_wheels and right_wheels both name {both}; each wheel drives one side")
    joints = {j.name: j for j in kinematics.joints}
    limits = {j.get("name"): j.find("limit") for j in parse_urdf(urdf).findall("joint")}
    frames = kinematics.forward(np.zeros((1, len(kinematics.joints))))
    y = {}
    for name in (*left, *right):
        joint = joints[name]
        what = f"{where}: wheel joint {name!r} of {source}"
        if joint.kind == "prismatic":
            raise ValueError(f"{what} is prismatic; a wheel turns (revolute or continuous)")
        limit = limits[name]
        if joint.kind == "revolute" and limit is not None:
            lower, upper = float(limit.get("lower", 0.0)), float(limit.get("upper", -1.0))  # pybullet's defaults
            if lower <= upper < lower + FREE_SPAN:
                raise ValueError(f"{what} is revolute with <limit lower={lower:g} upper={upper:g}>, which pybullet "
                                 "stops it at; a wheel turns freely: make it continuous")
        frame = frames[joint.child][0]
        axis = frame[:3, :3] @ joint.axis
        if axis[1] < math.cos(AXLE_TOLERANCE):
            raise ValueError(f"{what} turns about {_words(axis)} in the base frame; {_cause(axis)}")
        y[name] = float(frame[1, 3])
    wrong = [name for name in left if y[name] <= 0.0] + [name for name in right if y[name] >= 0.0]
    if wrong:
        swapped = all(y[name] < 0.0 for name in left) and all(y[name] > 0.0 for name in right)
        cause = ("the lists are swapped: with +x forward, the left side is +y; swap left_wheels and right_wheels"
                 if swapped else "each list must name the wheels of its own side (left: +y, right: -y, +x forward)")
        raise ValueError(f"{where}: wheel joints {wrong} of {source} sit at y = {[round(y[n], 4) for n in wrong]} in "
                         f"the base frame, on the wrong side or the centreline: {cause}")


def _words(axis: np.ndarray) -> str:
    return f"({', '.join(f'{v:.3g}' for v in axis)})"


def _cause(axis: np.ndarray) -> str:
    """The likely cause of a wheel axle off +y, in words."""
    convention = "clutter-gym drives a base along its +x with its wheels' axles along +y (REP 103, docs/robots.md)"
    if abs(axis[2]) >= max(abs(axis[0]), abs(axis[1])):
        return f"its axle stands upright, so it cannot roll: {convention}"
    if abs(axis[0]) > abs(axis[1]):
        return (f"the axles lie along x, so the base drives along y: {convention}; turn the URDF's base so +x points "
                "forward")
    if axis[1] < 0.0:
        return (f"a positive wheel speed rolls it backward: {convention}; flip the joint's <axis>, or, if the base's "
                "front is -x, turn the URDF's base so +x points forward")
    return f"the wheel is toed in or out by more than {math.degrees(AXLE_TOLERANCE):g} degrees: {convention}"


def check_wheel_geometry(kinematics: UrdfKinematics, elements: list[CollisionElement], wheel_links: Sequence[str],
                         radius: float, given: bool, source: Path, where: str) -> None:
    """Refuse a ``radius`` more than :data:`RADIUS_TOLERANCE` from the reach of
    each wheel's collision shapes below its axle (``given``: the spec gave it, else it was derived from the wheel
    links' collision cylinders), and another link whose collision shapes reach more than :data:`GROUND_TOLERANCE`
    below a wheel's lowest point (joints at zero)."""
    frames = kinematics.forward(np.zeros((1, len(kinematics.joints))))
    lowest: dict[str, float] = {}
    for e in elements:
        z = _lowest(e, frames[e.link][0])
        lowest[e.link] = min(lowest.get(e.link, math.inf), z)
    for link in wheel_links:
        reach = float(frames[link][0, 2, 3]) - lowest[link]
        if not abs(radius - reach) <= RADIUS_TOLERANCE * reach:
            said = (f"wheel_radius {radius:g} m" if given else
                    f"wheel_radius, derived from the wheel links' collision cylinders, is {radius:.4g} m, but")
            raise ValueError(f"{where}: {said} disagrees with wheel link {link!r} of {source}, whose collision shape "
                             f"reaches {reach:.4g} m below its axle (more than {RADIUS_TOLERANCE:.0%} apart): "
                             + ("give the radius the wheels have, or leave wheel_radius out" if given else
                                "turn its cylinder so its axis is the axle, or give wheel_radius"))
    wheels = {link for link in kinematics.links if _on_a_wheel(link, wheel_links, kinematics)}
    floor = max(lowest[link] for link in wheel_links)
    others = {link: z for link, z in lowest.items() if link not in wheels and z < floor - GROUND_TOLERANCE}
    if others:
        link = min(others, key=others.__getitem__)
        raise ValueError(f"{where}: link {link!r} of {source} reaches {1e3 * (floor - others[link]):.1f} mm below "
                         f"the wheels' lowest points (z = {others[link]:.4f} m against {floor:.4f} m in the base "
                         f"frame, joints at zero): the base would rest on it and its wheels would not grip; raise it, "
                         f"or check the wheels' joint origins and radii")


def check_wheel_links(masses: Mapping[str, float], elements: list[CollisionElement], root: str,
                      wheel_links: Sequence[str], source: Path, where: str) -> None:
    """Refuse a wheel link without collision geometry, and a zero mass on the root link or a wheel (a link without
    ``<inertial>`` is not in ``masses``: it weighs a token gram). Measured: pybullet holds a base whose root weighs
    0 kg still, and one whose wheels weigh 0 kg does not move."""
    shaped = {e.link for e in elements}
    for link in wheel_links:
        if link not in shaped:
            raise ValueError(f"{where}: wheel link {link!r} of {source} has no collision geometry, so it cannot "
                             "touch the floor")
    for link in (root, *wheel_links):
        if masses.get(link) == 0.0:
            part, why = (("root link", "pybullet holds a body whose base weighs nothing still") if link == root else
                         ("wheel link", "wheels that weigh nothing do not drive the base in pybullet"))
            raise ValueError(f"{where}: {part} {link!r} of {source} has <mass value=0>: {why}; give its mass, or "
                             "leave its <inertial> out (a token gram)")


def _on_a_wheel(link: str, wheel_links: Sequence[str], kinematics: UrdfKinematics) -> bool:
    """Whether ``link`` is a wheel or turns with one (a hub, a tyre)."""
    while link != kinematics.root:
        if link in wheel_links:
            return True
        link = kinematics.parent[link]
    return False


def _lowest(e: CollisionElement, link_frame: np.ndarray) -> float:
    """The lowest z, in the base frame, of collision element ``e`` on a link at ``link_frame``."""
    rotation = link_frame[:3, :3] @ quat_to_matrix(e.quaternion)
    centre = link_frame[:3, :3] @ e.position + link_frame[:3, 3]
    if e.kind == "box":
        return float(centre[2] - 0.5 * np.abs(rotation[2]) @ np.array(e.size))
    if e.kind == "mesh":
        return float(np.min(np.asarray(e.mesh.vertices) @ rotation[2] + centre[2]))  # type: ignore[union-attr]
    radius, length = e.size[0], (e.size[1] if len(e.size) > 1 else 0.0)
    up = abs(rotation[2, 2])  # the element's axis' vertical share
    if e.kind == "cylinder":
        return float(centre[2] - 0.5 * length * up - radius * math.sqrt(max(0.0, 1.0 - up * up)))
    return float(centre[2] - 0.5 * length * up - radius)  # sphere (length 0) and capsule
