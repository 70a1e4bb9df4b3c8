"""Collision geometry of a URDF's links as FCL shapes (primitives: box, cylinder, sphere).

Each ``<collision>`` element becomes one :class:`CollisionElement` carrying its link name and its origin in the
link frame. Mesh elements and fidelity levels come with the collision-layer work (issue 3); a URDF that needs
them is rejected here with a clear error rather than approximated silently.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import fcl
import numpy as np

from clutter_gym.transforms import rpy_quat


@dataclass(frozen=True)
class CollisionElement:
    """One collision primitive of a link.

    Attributes:
        link: URDF link name.
        geometry: the FCL shape in its own frame (cylinders along z, centred).
        position: (3,) element origin in the link frame, metres.
        quaternion: (4,) element orientation in the link frame, (x, y, z, w).
    """

    link: str
    geometry: fcl.CollisionGeometry
    position: np.ndarray
    quaternion: np.ndarray


def _floats(text: str | None, n: int, default: float) -> np.ndarray:
    if text is None:
        return np.full(n, default)
    values = np.array([float(v) for v in text.split()])
    if values.shape != (n,):
        raise ValueError(f"expected {n} numbers, got {text!r}")
    return values


def _shape(geometry: ET.Element, where: str) -> fcl.CollisionGeometry:
    child = next(iter(geometry), None)
    if child is None:
        raise ValueError(f"{where}: <geometry> is empty")
    tag, a = child.tag, child.attrib
    if tag == "box":
        return fcl.Box(*_floats(a.get("size"), 3, 0.0))
    if tag == "cylinder":
        return fcl.Cylinder(float(a["radius"]), float(a["length"]))
    if tag == "sphere":
        return fcl.Sphere(float(a["radius"]))
    raise ValueError(f"{where}: <{tag}> collision geometry is not supported yet (box, cylinder, sphere are)")


def load_collision_elements(urdf: str | Path) -> list[CollisionElement]:
    """Every collision element of every link of ``urdf``, in document order.

    Raises:
        ValueError: the URDF cannot be parsed or uses an unsupported geometry (the message names the link).
    """
    try:
        root = ET.parse(urdf).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"cannot parse URDF {urdf}: {exc}") from exc
    elements = []
    for link in root.iter("link"):
        name = link.attrib["name"]
        for i, col in enumerate(link.findall("collision")):
            where = f"{urdf} link {name!r} collision {i}"
            origin = col.find("origin")
            attrs = origin.attrib if origin is not None else {}
            geometry = col.find("geometry")
            if geometry is None:
                raise ValueError(f"{where}: missing <geometry>")
            elements.append(
                CollisionElement(
                    link=name,
                    geometry=_shape(geometry, where),
                    position=_floats(attrs.get("xyz"), 3, 0.0),
                    quaternion=rpy_quat(*_floats(attrs.get("rpy"), 3, 0.0)),
                )
            )
    return elements
