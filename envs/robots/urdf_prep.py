"""A robot's URDF made ready for an env: sensor links added where the robot's spec mounts them, xacro leftovers
resolved, and links without mass given a token one, written once into the user cache.

URDFs from other projects rarely carry the links an env's sensors sit on (ClutterNav's LIDAR casts from
``lidar_link``), some keep unexpanded ``$(optenv NAME default)`` substitutions from xacro (pybullet_data's Husky
does), and pybullet gives every link without an ``<inertial>`` 1 kg (six phantom kilograms on the Husky). The
prepared copy fixes exactly those three things and nothing else: it adds a fixed link per sensor mount,
takes each ``optenv``'s default (never the environment: a URDF must not change with a shell variable), and gives
mass-less links 1 g. The meshes it names (by relative, ``package://`` or ``file://`` paths) are copied beside it
and named by paths relative to it, so its text, and with it the cache key of everything derived from it (the
allowed-collision matrix), is the same on every machine.
"""

from __future__ import annotations

import hashlib
import shutil
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from clutter_gym.collision.urdf_geometry import parse_urdf, resolve_mesh
from clutter_gym.util.atomic import atomic_path, write_text_atomically
from clutter_gym.util.cache_dir import user_cache_dir

#: kg of a link the URDF gives no mass (pybullet's default would be 1 kg)
TOKEN_MASS = 1e-3


@dataclass(frozen=True)
class Mount:
    """A sensor link to add: ``name`` on ``parent`` at ``xyz`` (metres) and ``rpy`` (radians) in its frame."""

    name: str
    parent: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


def prepared_urdf(source: str | Path, name: str, mounts: tuple[Mount, ...] = ()) -> Path:
    """The prepared copy of ``source`` (see the module docstring), made on first use.

    Raises:
        ValueError: the URDF cannot be parsed, a mount names a parent link the URDF does not have or a link it
            already has, or a mesh it names is missing (each message names the URDF and what it offers).
    """
    source = Path(source)
    root = parse_urdf(source)
    links = [link.get("name") for link in root.findall("link")]
    for mount in mounts:
        if mount.parent not in links:
            raise ValueError(f"{source}: no link {mount.parent!r} to mount {mount.name!r} on; its links: {links}")
        if mount.name in links:
            raise ValueError(f"{source}: already has a link {mount.name!r}; mount the sensor on it instead")
    copies = _mesh_copies(root, source)  # before the text: the copy names its meshes by their new paths
    text = _prepared_text(root, mounts)
    digest = hashlib.sha256(text.encode())
    for relative, path in sorted(copies.items()):
        digest.update(relative.encode() + path.read_bytes())
    folder = user_cache_dir("robots") / f"{name}-{digest.hexdigest()[:16]}"
    target = folder / f"{name}.urdf"
    if not target.is_file():
        for relative, path in copies.items():  # each file whole or not at all: another process may load this copy
            with atomic_path(folder / relative) as tmp:
                shutil.copyfile(path, tmp)
        write_text_atomically(target, text)  # last: the URDF's presence says its meshes are there
    return target


def _mesh_copies(root: ET.Element, source: Path) -> dict[str, Path]:
    """Name every ``<mesh filename>`` (relative, ``package://`` or ``file://``) by a path relative to the copy: its
    path under the URDF's folder, or ``meshes/`` for a file outside it; returns {that path: the file it copies}.

    Raises:
        ValueError: a mesh file is missing (the message says where it looked).
    """
    copies: dict[str, Path] = {}
    for element in root.iter("mesh"):
        filename = element.get("filename", "")
        try:
            path = resolve_mesh(filename, source)
        except ValueError as error:
            raise ValueError(f"{source}: {error}") from None
        try:
            relative = path.relative_to(source.parent.resolve()).as_posix()
        except ValueError:  # outside the URDF's folder: keep its name, made unique by its folder's
            relative = f"meshes/{hashlib.sha256(str(path.parent).encode()).hexdigest()[:8]}/{path.name}"
        copies[relative] = path
        element.set("filename", relative)
    return copies


def _prepared_text(root: ET.Element, mounts: tuple[Mount, ...]) -> str:
    for mount in mounts:
        ET.SubElement(root, "link", name=mount.name)
        joint = ET.SubElement(root, "joint", name=f"{mount.name}_joint", type="fixed")
        ET.SubElement(joint, "parent", link=mount.parent)
        ET.SubElement(joint, "child", link=mount.name)
        ET.SubElement(joint, "origin", xyz=" ".join(map(repr, mount.xyz)), rpy=" ".join(map(repr, mount.rpy)))
    for link in root.findall("link"):
        if link.find("inertial") is None:
            inertial = ET.SubElement(link, "inertial")
            ET.SubElement(inertial, "mass", value=f"{TOKEN_MASS}")
            ET.SubElement(inertial, "inertia", ixx="1e-7", iyy="1e-7", izz="1e-7", ixy="0", ixz="0", iyz="0")
    return ET.tostring(root, encoding="unicode")
