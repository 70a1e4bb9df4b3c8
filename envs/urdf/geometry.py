"""Collision elements of a URDF's links as plain data: primitives by their sizes, meshes loaded with trimesh.

Each ``<collision>`` element becomes one :class:`CollisionElement` carrying its link name and its origin in the
link frame. Supported geometry: ``box``, ``cylinder``, ``sphere``, ``capsule`` (pybullet's extension: a cylinder
of ``length`` between two hemispheres) and ``mesh`` (any format trimesh reads: OBJ, STL, DAE, ...; ``scale``
honoured). Which FCL shape an element becomes is the fidelity level's choice (:mod:`.fidelity`).

Mesh file names resolve as pybullet resolves them: ``package://a/b.obj`` and relative names against the URDF's
folder (and its parents, for ``package://<pkg>/...`` layouts), ``file://`` and absolute paths as they are.
"""

from __future__ import annotations

import hashlib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from clutter_gym.urdf.checks import check_urdf, resolve_optenv
from clutter_gym.util.transforms import rpy_quat

if TYPE_CHECKING:  # loaded by _load_mesh, when a URDF has a mesh: trimesh imports FCL if it finds it
    import trimesh

KINDS = ("box", "cylinder", "sphere", "capsule", "mesh")
#: relative to the mesh's size: a triangle's area (over the diagonal squared) and a mesh's thinnest spread of vertices
#: (over its widest) at or below this have none
MIN_AREA = 1e-9
#: metres: a mesh (as scaled by its URDF) narrower than this is refused. trimesh drops triangles under an absolute
#: area tolerance, so a hull of a far smaller mesh loses its faces (docs/collision.md, "User meshes").
MIN_MESH_SIZE = 1e-3
#: a mesh (as scaled) whose thinnest extent is at most this share of its widest is refused as nearly flat: it encloses
#: almost no volume, and the minimum enclosing sphere's Qhull step loses its thickness in round-off.
MIN_THICKNESS = 1e-3
#: triangles a collision mesh may have. The fidelity levels, the allowed-collision matrix and pybullet all work on
#: the whole mesh, so a make's time and memory grow with it (docs/robots.md gives the figures); a mesh is refused
#: above this, not simplified here, as pybullet would still load the full one and the two engines would disagree.
MAX_FACES = 100_000


@dataclass(frozen=True, eq=False)
class CollisionElement:
    """One collision element of a link.

    Attributes:
        link: URDF link name.
        kind: one of :data:`KINDS`.
        size: box (sx, sy, sz) full extents; cylinder and capsule (radius, length), length along the element's
            z axis (a capsule's length excludes its caps); sphere (radius,); mesh: the scaled mesh's bounding-box
            extents. Metres.
        position: (3,) element origin in the link frame, metres.
        quaternion: (4,) element orientation in the link frame, (x, y, z, w).
        mesh: the scaled triangle mesh in the element frame (meshes only).
        source: the resolved mesh file (meshes only).
    """

    link: str
    kind: str
    size: tuple[float, ...]
    position: np.ndarray
    quaternion: np.ndarray
    mesh: trimesh.Trimesh | None = None
    source: Path | None = None


def parse_floats(text: str | None, n: int, default: float, where: str) -> np.ndarray:
    if text is None:
        return np.full(n, default)
    try:
        values = np.array([float(v) for v in text.split()])
    except ValueError:
        raise ValueError(f"{where}: expected {n} numbers, got {text!r}") from None
    if values.shape != (n,) or not np.all(np.isfinite(values)):
        raise ValueError(f"{where}: expected {n} finite numbers, got {text!r}")
    return values


def _positive(attrib: dict[str, str], key: str, where: str) -> float:
    if key not in attrib:
        raise ValueError(f"{where}: missing attribute {key!r}")
    value = parse_floats(attrib[key], 1, 0.0, f"{where} {key}")[0]
    if value <= 0.0:
        raise ValueError(f"{where}: {key} must be > 0 metres, got {value}")
    return float(value)


def resolve_mesh(filename: str, urdf: Path) -> Path:
    """The file a URDF mesh ``filename`` refers to.

    Raises:
        ValueError: no such file (the message lists where it looked).
    """
    if filename.startswith("file://"):
        candidates = [Path(filename[len("file://"):])]
    elif filename.startswith("package://"):
        rest = Path(filename[len("package://"):])
        candidates = [urdf.parent / rest] + [p / rest.relative_to(rest.parts[0]) for p in urdf.parents if rest.parts]
        candidates += [p / rest for p in urdf.parents]
    else:
        candidates = [Path(filename) if Path(filename).is_absolute() else urdf.parent / filename]
    for path in candidates:
        if path.is_file():
            return path.resolve()
    raise ValueError(f"mesh {filename!r} not found (looked at {[str(p) for p in candidates[:4]]})")


@lru_cache(maxsize=64)
def _load_mesh(path: Path) -> trimesh.Trimesh:
    """One triangle mesh from ``path`` (scenes are merged), its triangles wound consistently; cached per process,
    never mutated.

    Raises:
        ValueError: the mesh has more than :data:`MAX_FACES` triangles (counted on a quick read before the full
            one), none, none of positive area, or all of its vertices in one plane (no solid to collide with or to
            take a hull of); the message names the file.
    """
    faces = _face_count(path)
    if faces > MAX_FACES:
        raise ValueError(f"mesh {path} has {faces:,} triangles, more than the {MAX_FACES:,} a collision mesh may "
                         "have: simplify it (e.g. trimesh's simplify_quadric_decimation, or MeshLab) or model the "
                         "link with primitives")
    import trimesh

    loaded = trimesh.load(path, force="mesh", process=True)
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"mesh {path} holds no triangles")
    scale = float(np.linalg.norm(loaded.extents))
    if not (loaded.area_faces > MIN_AREA * scale**2).any():
        raise ValueError(f"mesh {path} has no triangle of positive area")
    spans = np.linalg.svd(loaded.vertices - loaded.vertices.mean(axis=0), compute_uv=False)
    if spans[-1] <= MIN_AREA * spans[0]:
        raise ValueError(f"mesh {path} is flat: every vertex lies in one plane, so it encloses no volume")
    trimesh.repair.fix_normals(loaded)  # one winding: a surface sampled by area-weighted normals needs it
    return loaded


def _face_count(path: Path) -> int:
    """How many triangles the mesh file holds: a binary STL's header says so (its size confirms it is one), so a
    large one is refused without reading its triangles; any other file is read without processing."""
    size = path.stat().st_size
    with path.open("rb") as file:
        head = file.read(84)
    if len(head) == 84 and size == 84 + 50 * int.from_bytes(head[80:], "little"):
        return int.from_bytes(head[80:], "little")
    import trimesh

    return len(getattr(trimesh.load(path, force="mesh", process=False), "faces", ()))


def check_solid(mesh: trimesh.Trimesh, what: str) -> None:
    """Refuse a mesh too small or too thin to build every fidelity level's shape from (its extents are measured
    along the principal axes of its vertices, so a turned plate counts as thin).

    Raises:
        ValueError: starting with ``what`` (the element and the file), naming the limit.
    """
    vertices = np.asarray(mesh.vertices, dtype=float)
    centred = vertices - vertices.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2]
    extents = np.ptp(centred @ axes.T, axis=0)
    wide, thick = float(extents.max()), float(extents.min())
    if wide < MIN_MESH_SIZE:
        raise ValueError(f"{what} is {wide:.3g} m across, under the {MIN_MESH_SIZE:g} m a collision mesh needs "
                         f"(check the URDF's scale and the file's units)")
    if thick <= MIN_THICKNESS * wide:
        raise ValueError(f"{what} is nearly flat: {thick:.3g} m thick and {wide:.3g} m wide, at most "
                         f"{MIN_THICKNESS:g} of its width; give it thickness or model it as a box")


def _element(col: ET.Element, link: str, urdf: Path, where: str) -> CollisionElement:
    origin = col.find("origin")
    attrs = origin.attrib if origin is not None else {}
    position = parse_floats(attrs.get("xyz"), 3, 0.0, f"{where} origin xyz")
    quaternion = rpy_quat(*parse_floats(attrs.get("rpy"), 3, 0.0, f"{where} origin rpy"))
    geometry = col.find("geometry")
    child = next(iter(geometry), None) if geometry is not None else None
    if child is None:
        raise ValueError(f"{where}: missing or empty <geometry>")
    tag, a = child.tag, child.attrib
    if tag == "box":
        extents = parse_floats(a.get("size"), 3, 0.0, f"{where} box size")
        if np.any(extents <= 0):
            raise ValueError(f"{where}: box size must be > 0 metres on every axis, got {a.get('size')!r}")
        return CollisionElement(link, "box", tuple(extents.tolist()), position, quaternion)
    if tag in ("cylinder", "capsule"):
        size = (_positive(a, "radius", where), _positive(a, "length", where))
        return CollisionElement(link, tag, size, position, quaternion)
    if tag == "sphere":
        return CollisionElement(link, "sphere", (_positive(a, "radius", where),), position, quaternion)
    if tag == "mesh":
        if "filename" not in a:
            raise ValueError(f"{where}: <mesh> has no filename")
        source = resolve_mesh(a["filename"], urdf)
        scale = parse_floats(a.get("scale"), 3, 1.0, f"{where} mesh scale")
        if np.any(scale == 0):
            raise ValueError(f"{where}: mesh scale must be non-zero, got {a.get('scale')!r}")
        try:
            mesh = _load_mesh(source).copy()
        except Exception as exc:  # trimesh raises many types for unreadable files
            raise ValueError(f"{where}: cannot read mesh {source}: {exc}") from exc
        mesh.apply_scale(scale)
        check_solid(mesh, f"{where}: mesh {source}")
        return CollisionElement(link, "mesh", tuple(mesh.extents.tolist()), position, quaternion, mesh, source)
    raise ValueError(f"{where}: <{tag}> collision geometry is not supported ({', '.join(KINDS)} are)")


def load_collision_elements(urdf: str | Path) -> list[CollisionElement]:
    """Every collision element of every link of ``urdf``, in document order.

    Raises:
        ValueError: the URDF is missing, cannot be parsed, or has an unsupported or malformed element (the
            message names the link and the element).
    """
    urdf = Path(urdf)
    root = parse_urdf(urdf)
    elements = []
    for link in root.findall("link"):
        name = link.attrib["name"]  # every link has one: parse_urdf checked
        for i, col in enumerate(link.findall("collision")):
            elements.append(_element(col, name, urdf, f"{urdf.name} link {name!r} collision {i}"))
    return elements


def parse_urdf(urdf: Path) -> ET.Element:
    """The URDF's elements, its xacro ``optenv`` defaults taken, once it has passed every check of
    :mod:`.checks` (a tree, finite numbers, no xacro left): what every reader of a URDF in the package reads.

    Raises:
        ValueError: the file is missing, is not XML, or fails a check (the message names the file and the element).
    """
    if not urdf.is_file():
        raise ValueError(f"URDF not found: {urdf}")
    try:
        root = ET.parse(urdf).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"cannot parse URDF {urdf}: {exc}") from exc
    resolve_optenv(root)
    check_urdf(root, urdf)
    return root


def urdf_digest(urdf: str | Path) -> str:
    """SHA-256 of the URDF text and every mesh file its collision elements use (cache key of derived data)."""
    urdf = Path(urdf)
    digest = hashlib.sha256(urdf.read_bytes())
    for source in sorted({str(e.source) for e in load_collision_elements(urdf) if e.source is not None}):
        digest.update(Path(source).read_bytes())
    return digest.hexdigest()
