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

What it reads and writes is bounded (docs/robots.md, "The cache, names and meshes"): ``name`` becomes a file name,
so it must be a plain one (:func:`~clutter_gym.util.checks.check_file_name`); a mesh is read only inside the URDF's
folder or a package root the user grants, and only when it is a regular mesh file of bounded size
(:mod:`clutter_gym.util.mesh_files`); nothing is copied before every mesh has passed. The copy's folder is named by
the digest of what goes in it, and what is there is checked against that on every use: a cached file edited,
truncated or missing is written again.
"""

from __future__ import annotations

import hashlib
import os
import stat
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from clutter_gym.urdf.geometry import parse_urdf
from clutter_gym.util.atomic import atomic_path
from clutter_gym.util.cache_dir import user_cache_dir
from clutter_gym.util.checks import check_file_name
from clutter_gym.util.mesh_files import MeshFile, checked_mesh, confined_mesh, copy_checked, file_digest, mesh_label

#: kg of a link the URDF gives no mass (pybullet's default would be 1 kg)
TOKEN_MASS = 1e-3


@dataclass(frozen=True)
class Mount:
    """A sensor link to add: ``name`` on ``parent`` at ``xyz`` (metres) and ``rpy`` (radians) in its frame."""

    name: str
    parent: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


def prepared_urdf(source: str | Path, name: str, mounts: tuple[Mount, ...] = (),
                  package_roots: Mapping[str, Path] | None = None) -> Path:
    """The prepared copy of ``source`` (see the module docstring), made on first use and checked on every use;
    ``package_roots`` grants the folders ``package://<name>/...`` meshes may also come from.

    Raises:
        ValueError: ``name`` is not a plain file name, the URDF cannot be parsed, a mount names a parent link the
            URDF does not have or a link it already has, or a mesh it names is missing or refused (each message
            names the URDF and what it offers or what was refused).
    """
    source = Path(source)
    check_file_name(f"{source}: name", name)
    root = parse_urdf(source)
    links = [link.get("name") for link in root.findall("link")]
    for mount in mounts:
        if mount.parent not in links:
            raise ValueError(f"{source}: no link {mount.parent!r} to mount {mount.name!r} on; its links: {links}")
        if mount.name in links:
            raise ValueError(f"{source}: already has a link {mount.name!r}; mount the sensor on it instead")
    meshes = _mesh_copies(root, source, package_roots or {})  # before the text: it names its meshes' new paths
    text = _prepared_text(root, mounts).encode()
    digest = hashlib.sha256(text)
    for relative, mesh in sorted(meshes.items()):
        digest.update(f"\0{relative}\0{mesh.digest}".encode())
    folder = user_cache_dir("robots") / f"{name}-{digest.hexdigest()[:16]}"
    target = folder / f"{name}.urdf"
    for relative, mesh in meshes.items():  # each file whole or not at all: another process may load this copy
        if not _holds(folder / relative, mesh.size, mesh.digest):
            copy_checked(mesh, folder / relative, f"{source}: mesh {relative}")
    text_digest = hashlib.sha256(text).hexdigest()
    if not _holds(target, len(text), text_digest):  # last: the URDF's presence says its meshes are there
        with atomic_path(target) as tmp:
            tmp.write_bytes(text)
            os.chmod(tmp, stat.S_IMODE(os.stat(tmp).st_mode) & stat.S_IMODE(os.stat(source).st_mode))
    return target


def _holds(path: Path, size: int, digest: str) -> bool:
    """Whether the cached ``path`` is a regular file (not a link) of ``size`` bytes with SHA-256 ``digest``."""
    try:
        info = os.lstat(path)
        return stat.S_ISREG(info.st_mode) and info.st_size == size and file_digest(path, size, "") == digest
    except (OSError, ValueError):
        return False


def _mesh_copies(root: ET.Element, source: Path, package_roots: Mapping[str, Path]) -> dict[str, MeshFile]:
    """Resolve and check every ``<mesh filename>`` (:func:`~clutter_gym.util.mesh_files.confined_mesh`), and name
    it by a path relative to the copy: its path under the URDF's folder, or ``meshes/<folder digest>/`` for a file
    of a granted package root; returns {that path: the checked file}.

    Raises:
        ValueError: a mesh is missing or refused (the message names it and the URDF).
    """
    copies: dict[str, MeshFile] = {}
    home = source.parent.resolve()
    for element in root.iter("mesh"):
        filename = element.get("filename", "")
        path = confined_mesh(filename, source, package_roots)
        if path.is_relative_to(home):
            relative = path.relative_to(home).as_posix()
        else:  # in a granted package root: keep its name, made unique by its folder's
            relative = f"meshes/{hashlib.sha256(str(path.parent).encode()).hexdigest()[:8]}/{path.name}"
        if relative not in copies:
            copies[relative] = checked_mesh(path, mesh_label(source, filename))
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
