"""The mesh files a URDF names, found only where its user allows, checked before anything reads or copies them.

A URDF is often someone else's file, and its ``<mesh filename>`` is a path it chooses: ``file:///``, an absolute
path, ``..`` or a symbolic link could name any file of the user's (``~/.ssh/id_rsa``, ``/proc/self/environ``), and
a "mesh" of gigabytes or a FIFO would make its reader run out of memory or wait forever. So a mesh resolves only
inside the URDF's own folder, or inside a package root its user grants by name (``package://<name>/...``); the path
is resolved (links followed) before the containment check, so no link leads out. The file must then be a regular
file of a mesh format pybullet reads (:data:`MESH_SUFFIXES`) and at most :data:`MAX_MESH_BYTES`. Each refusal is
one line naming the mesh, as the URDF writes it, and the URDF. The preparation of a spec's URDF
(:mod:`clutter_gym.robots.urdf_prep`) reads meshes only through here; what it writes names its meshes beside it, so
the collision layer, which reads that copy and the URDFs the package ships, finds them there.

:func:`file_digest` hashes in chunks and reads no more than the size it was given (a file that grows or shrinks
meanwhile is refused), and :func:`copy_checked` copies a checked file into place only when the copy's digest is the
one the source had, keeping the source's permissions or stricter ones.
"""

from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from clutter_gym.util.atomic import atomic_path

#: the formats pybullet reads a URDF's meshes in
MESH_SUFFIXES = (".obj", ".stl", ".dae")
#: bytes: the largest mesh file read (docs/robots.md, "The cache, names and meshes")
MAX_MESH_BYTES = 64 << 20
_CHUNK = 1 << 20


@dataclass(frozen=True)
class MeshFile:
    """A mesh file that passed every check: its resolved ``path``, ``size`` in bytes, permission bits (``mode``)
    and SHA-256 ``digest`` (hex)."""

    path: Path
    size: int
    mode: int
    digest: str


def mesh_label(urdf: Path, filename: str) -> str:
    """How messages name a mesh: the URDF, and the name as the URDF writes it."""
    return f"{urdf}: <mesh filename={filename!r}>"


def confined_mesh(filename: str, urdf: Path, package_roots: Mapping[str, Path] | None = None) -> Path:
    """The file a URDF ``<mesh filename>`` names: ``package://<name>/rest`` in the granted root of ``<name>`` (the
    folder ``package_roots`` maps it to), else as ``<name>/rest`` or ``rest`` in the URDF's folder (the layouts of
    pybullet_data's URDFs); a relative name in the URDF's folder; ``file://`` and absolute paths as they are. The
    file found must lie inside the URDF's folder or a granted root; :func:`checked_mesh` checks what it is.

    Raises:
        ValueError: the mesh lies outside those folders, or is missing (one line naming the mesh and the URDF).
    """
    where = mesh_label(urdf, filename)
    home = urdf.parent.resolve()
    roots = {name: Path(root).resolve() for name, root in (package_roots or {}).items()}
    package = ""
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        candidates = ([roots[package] / rest] if package in roots else []) + [home / package / rest, home / rest]
    else:
        name = filename[len("file://"):] if filename.startswith("file://") else filename
        candidates = [home / name]  # an absolute name stays itself
    allowed = [home, *roots.values()]
    for candidate in candidates:
        path = candidate.resolve()
        if not any(path.is_relative_to(root) for root in allowed):
            if _exists(path):
                raise ValueError(f"{where} is {path}, outside the URDF's folder {home} and the granted package "
                                 f"roots {sorted(roots)}; grant its package with package_roots")
            continue
        if _exists(path):
            return path
    hint = ""
    if package and package not in roots:
        hint = f"; a package outside the URDF's folder needs its folder granted: package_roots: {{{package}: ...}}"
    raise ValueError(f"{where} not found (looked at {[str(p) for p in candidates]}){hint}")


def _exists(path: Path) -> bool:
    try:
        return path.exists()
    except OSError:  # a folder on the way that may not be searched: nothing to find there
        return False


def check_mesh_file(path: Path, where: str) -> os.stat_result:
    """``path``'s status when it is a regular file of a mesh format (:data:`MESH_SUFFIXES`) of at most
    :data:`MAX_MESH_BYTES`; else a ValueError starting with ``where``."""
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        raise ValueError(f"{where} is {path}, not a regular file")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise ValueError(f"{where} is {path}, not a mesh file pybullet reads ({', '.join(MESH_SUFFIXES)})")
    if info.st_size > MAX_MESH_BYTES:
        raise ValueError(f"{where} is {path}, {info.st_size:,} bytes: over the {MAX_MESH_BYTES:,} a mesh may have")
    return info


def checked_mesh(path: Path, where: str) -> MeshFile:
    """``path`` checked (:func:`check_mesh_file`) and hashed; a file that cannot be read is a ValueError too."""
    try:
        info = check_mesh_file(path, where)
        return MeshFile(path, info.st_size, stat.S_IMODE(info.st_mode), file_digest(path, info.st_size, where))
    except OSError as error:
        raise ValueError(f"{where}: cannot read {path}: {error.strerror or error}") from None


def file_digest(path: Path, size: int, where: str) -> str:
    """SHA-256 (hex) of ``path``, which must hold exactly ``size`` bytes; read in chunks, never past ``size``.

    Raises:
        ValueError: the file is not a regular file (now) or does not hold ``size`` bytes (it changed).
    """
    with _open_regular(path, where) as file:
        return _hash_exactly(file, size, f"{where}: {path}", None)


def copy_checked(mesh: MeshFile, target: Path, where: str) -> None:
    """Copy ``mesh`` to ``target`` (whole or not at all), with the source's permission bits or stricter ones.

    Raises:
        ValueError: the source no longer holds what was checked (its size or digest changed).
    """
    with _open_regular(mesh.path, where) as source, atomic_path(target) as tmp:
        with open(tmp, "wb") as out:
            if _hash_exactly(source, mesh.size, f"{where}: {mesh.path}", out) != mesh.digest:
                raise ValueError(f"{where}: {mesh.path} changed while it was copied")
        os.chmod(tmp, stat.S_IMODE(os.stat(tmp).st_mode) & mesh.mode)


def _open_regular(path: Path, where: str) -> BinaryIO:
    """``path`` opened for reading without following a final link and without blocking on a FIFO, when it is a
    regular file."""
    file = os.fdopen(os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK), "rb")
    if not stat.S_ISREG(os.fstat(file.fileno()).st_mode):
        file.close()
        raise ValueError(f"{where}: {path} is not a regular file")
    return file


def _hash_exactly(file: BinaryIO, size: int, what: str, out: BinaryIO | None) -> str:
    """SHA-256 (hex) of the ``size`` bytes ``file`` holds, written on to ``out`` if given; ``what`` names the file
    in the error when it holds more or fewer."""
    digest, left = hashlib.sha256(), size
    while left > 0:
        chunk = file.read(min(_CHUNK, left))
        if not chunk:
            break
        digest.update(chunk)
        if out is not None:
            out.write(chunk)
        left -= len(chunk)
    if left or file.read(1):
        raise ValueError(f"{what} changed while it was read (it no longer holds {size:,} bytes)")
    return digest.hexdigest()
