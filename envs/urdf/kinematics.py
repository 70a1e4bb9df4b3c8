"""Forward kinematics of a URDF's link frames with numpy, batched over configurations.

The allowed-collision matrix samples thousands of joint configurations; computing their link frames here (one
vectorised pass per joint) keeps that sampling free of the simulator. The frames are the URDF link frames, the
same ones pybullet reports as ``worldLinkFramePosition`` (tested against it).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.urdf.geometry import parse_floats, parse_urdf
from clutter_gym.util.transforms import quat_to_matrix, rpy_quat

MOVING = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class Joint:
    """One URDF joint: ``child`` frame = ``parent`` frame * origin * motion(q) about/along ``axis``."""

    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray  # (4, 4)
    axis: np.ndarray  # (3,) unit vector in the joint frame
    lower: float
    upper: float


class UrdfKinematics:
    """Link frames of a URDF tree relative to its root link.

    Attributes:
        root: name of the root link.
        links: every link name, parents before children.
        joints: the moving joints (revolute, continuous, prismatic) in the order of ``q``'s columns.
    """

    def __init__(self, urdf: str | Path) -> None:
        root = parse_urdf(Path(urdf))
        joints = [_joint(j, Path(urdf).name) for j in root.findall("joint")]
        children = {j.child for j in joints}
        names = [link.attrib["name"] for link in root.findall("link")]
        roots = [n for n in names if n not in children]
        if len(roots) != 1:
            raise ValueError(f"{urdf}: expected one root link, found {roots}")
        self.root = roots[0]
        by_parent: dict[str, list[Joint]] = {}
        for j in joints:
            by_parent.setdefault(j.parent, []).append(j)
        self._order: list[Joint] = []  # joints parents-first
        frontier = [self.root]
        while frontier:
            link = frontier.pop(0)
            for j in by_parent.get(link, []):
                self._order.append(j)
                frontier.append(j.child)
        self.links = [self.root] + [j.child for j in self._order]
        self.joints = [j for j in joints if j.kind in MOVING]
        self.parent = {j.child: j.parent for j in joints}

    @property
    def lower(self) -> np.ndarray:
        return np.array([j.lower for j in self.joints])

    @property
    def upper(self) -> np.ndarray:
        return np.array([j.upper for j in self.joints])

    def forward(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Homogeneous link frames (n, 4, 4) for joint values ``q`` (n, n_joints), relative to the root link."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if q.shape[1] != len(self.joints):
            raise ValueError(f"q must have {len(self.joints)} columns (one per moving joint), got shape {q.shape}")
        column = {j.name: i for i, j in enumerate(self.joints)}
        frames = {self.root: np.broadcast_to(np.eye(4), (len(q), 4, 4))}
        for j in self._order:
            frame = frames[j.parent] @ j.origin
            if j.kind in MOVING:
                frame = frame @ _motion(j, q[:, column[j.name]])
            frames[j.child] = frame
        return frames


def _motion(j: Joint, values: np.ndarray) -> np.ndarray:
    out = np.broadcast_to(np.eye(4), (len(values), 4, 4)).copy()
    if j.kind == "prismatic":
        out[:, :3, 3] = values[:, None] * j.axis
        return out
    half = 0.5 * values
    quat = np.concatenate([np.sin(half)[:, None] * j.axis, np.cos(half)[:, None]], axis=1)
    out[:, :3, :3] = quat_to_matrix(quat)
    return out


def _joint(element: ET.Element, urdf: str) -> Joint:
    name = element.attrib.get("name", "?")
    where = f"{urdf} joint {name!r}"
    kind = element.attrib.get("type")
    if kind not in (*MOVING, "fixed"):
        raise ValueError(f"{where}: type {kind!r} is not supported (revolute, continuous, prismatic, fixed are)")
    parent, child = element.find("parent"), element.find("child")
    if parent is None or child is None:
        raise ValueError(f"{where}: needs <parent> and <child>")
    origin = element.find("origin")
    attrs = origin.attrib if origin is not None else {}
    transform = np.eye(4)
    transform[:3, :3] = quat_to_matrix(rpy_quat(*parse_floats(attrs.get("rpy"), 3, 0.0, f"{where} origin rpy")))
    transform[:3, 3] = parse_floats(attrs.get("xyz"), 3, 0.0, f"{where} origin xyz")
    axis_el = element.find("axis")
    axis = parse_floats(axis_el.attrib.get("xyz") if axis_el is not None else None, 3, 0.0, f"{where} axis")
    if axis_el is None:
        axis = np.array([1.0, 0.0, 0.0])
    norm = np.linalg.norm(axis)
    if kind in MOVING and norm == 0:
        raise ValueError(f"{where}: axis must be non-zero")
    limit = element.find("limit")
    lower, upper = -np.pi, np.pi
    if kind != "continuous" and limit is not None:
        lower = float(limit.attrib.get("lower", 0.0))
        upper = float(limit.attrib.get("upper", 0.0))
    return Joint(name, kind, parent.attrib["link"], child.attrib["link"], transform, axis / max(norm, 1e-300),
                 lower, upper)
