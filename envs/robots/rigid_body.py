"""Mass properties of a URDF whose links are all joined by fixed joints: one rigid body (a quadrotor's frame).

Read from the URDF's ``<inertial>`` and ``<joint><origin>`` elements with numpy, independently of pybullet, so a
controller can be tuned on the same numbers the physics engine is given and a test can check the engine's motion
against them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.datatypes import LinkStates
from clutter_gym.urdf.geometry import parse_floats, parse_urdf
from clutter_gym.util.transforms import quat_to_matrix, rpy_quat

_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


@dataclass(frozen=True)
class RigidBody:
    """Mass properties and link frames of a rigid URDF, in the root link's frame.

    Attributes:
        mass: total mass, kg.
        com: (3,) centre of mass, metres.
        inertia: (3, 3) inertia about ``com`` in the root link's axes, kg m^2.
        frames: each link's frame origin (3,) and rotation (3, 3) (columns: the link's axes), by link name.
        link_inertias: each link's mass (kg) and inertia (3, 3) (kg m^2) in its inertial frame, as the URDF gives
            them, by link name (links without an ``<inertial>`` element are left out).
        link_coms: each link's centre of mass (3,), metres (its frame origin for a link without ``<inertial>``),
            by link name.
        root: the root link's name (the link at the identity frame).
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    frames: dict[str, tuple[np.ndarray, np.ndarray]]
    link_inertias: dict[str, tuple[float, np.ndarray]]
    link_coms: dict[str, np.ndarray]
    root: str


class RigidFrames:
    """States of chosen links of a rigid body loaded as one merged pybullet body from its base's state alone: every
    link's pose and velocity follow from the base's, so nothing more needs reading from the physics engine (the same
    values as pybullet's link reads, to rounding).

    Args:
        body: the body's mass properties and link frames.
        links: names of the links, the rows of :meth:`link_states`.
    """

    def __init__(self, body: RigidBody, links: tuple[str, ...]) -> None:
        self._com = body.com
        self._origins = np.array([body.frames[n][0] for n in links])
        self._axes = np.array([body.frames[n][1] for n in links])
        self._levers = np.array([body.link_coms[n] for n in links]) - body.com  # from the centre of mass

    def link_states(self, com: tuple[float, float, float], rotation: np.ndarray,
                    linear_velocity: tuple[float, float, float], angular_velocity: tuple[float, float, float]
                    ) -> LinkStates:
        """The links' states (as :meth:`Sim.link_states` gives them).

        Args:
            com: the whole body's centre of mass (the merged body's base position in pybullet), world frame, metres.
            rotation: (3, 3) the root link's orientation.
            linear_velocity: velocity of ``com``, m/s.
            angular_velocity: rad/s, the same for every link.
        """
        origin = np.asarray(com) - rotation @ self._com
        wx, wy, wz = angular_velocity
        spin = np.array([[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]])  # w x v = spin @ v (np.cross costs more)
        return LinkStates(
            position=origin + self._origins @ rotation.T,
            rotation=np.matmul(rotation, self._axes),
            linear_velocity=np.asarray(linear_velocity) + self._levers @ (spin @ rotation).T,
            angular_velocity=np.array([angular_velocity] * len(self._origins), dtype=float),
        )


def _origin(element, where: str) -> tuple[np.ndarray, np.ndarray]:
    origin = element.find("origin") if element is not None else None
    attrib = origin.attrib if origin is not None else {}
    xyz = parse_floats(attrib.get("xyz"), 3, 0.0, f"{where} origin xyz")
    rpy = parse_floats(attrib.get("rpy"), 3, 0.0, f"{where} origin rpy")
    return xyz, quat_to_matrix(rpy_quat(*rpy))


def rigid_body(urdf: str | Path) -> RigidBody:
    """Compose the links of ``urdf`` into one body (parallel-axis theorem per link).

    Raises:
        ValueError: the URDF cannot be read (``parse_urdf`` refuses a negative mass), has a joint that is not fixed,
            or no mass.
    """
    urdf = Path(urdf)
    root = parse_urdf(urdf)
    parents: dict[str, tuple[str, np.ndarray, np.ndarray]] = {}
    for joint in root.findall("joint"):
        name = joint.attrib.get("name")
        if joint.attrib.get("type") != "fixed":
            raise ValueError(f"{urdf.name} joint {name!r}: only fixed joints make a rigid body")
        parents[joint.find("child").attrib["link"]] = (joint.find("parent").attrib["link"], *_origin(joint, name))
    frames: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def frame(link: str) -> tuple[np.ndarray, np.ndarray]:
        if link not in frames:
            if link in parents:
                parent, xyz, rot = parents[link]
                p, r = frame(parent)
                frames[link] = (p + r @ xyz, r @ rot)
            else:
                frames[link] = (np.zeros(3), np.eye(3))
        return frames[link]

    masses, centres, inertias = [], [], []
    link_inertias: dict[str, tuple[float, np.ndarray]] = {}
    link_coms: dict[str, np.ndarray] = {}
    for link in root.findall("link"):
        name = link.attrib["name"]
        p, r = frame(name)
        inertial = link.find("inertial")
        link_coms[name] = p
        if inertial is None:
            continue
        where = f"{urdf.name} link {name!r} inertial"
        mass = float(parse_floats(inertial.find("mass").attrib.get("value"), 1, 0.0, f"{where} mass")[0])
        xyz, rot = _origin(inertial, where)
        attrib = inertial.find("inertia").attrib
        ixx, ixy, ixz, iyy, iyz, izz = (float(attrib.get(k, 0.0)) for k in _INERTIA_KEYS)
        local = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        link_inertias[name] = (mass, local)
        axes = r @ rot
        masses.append(mass)
        centres.append(p + r @ xyz)
        link_coms[name] = centres[-1]
        inertias.append(axes @ local @ axes.T)
    total = float(sum(masses))
    if not total > 0.0:
        raise ValueError(f"{urdf.name}: its links weigh nothing: give the mass in an <inertial> element")
    com = sum(m * c for m, c in zip(masses, centres)) / total
    inertia = np.zeros((3, 3))
    for m, c, i in zip(masses, centres, inertias):
        d = c - com
        inertia += i + m * (d @ d * np.eye(3) - np.outer(d, d))
    return RigidBody(mass=total, com=com, inertia=inertia, frames=frames, link_inertias=link_inertias,
                     link_coms=link_coms, root=next(n for n in frames if n not in parents))
