"""FCL shapes for a robot's collision elements at a chosen fidelity level.

| level | a link becomes | a mesh element becomes | URDF primitives |
|---|---|---|---|
| ``sphere`` | one sphere enclosing all its elements | (part of the link sphere) | (part of the link sphere) |
| ``spheres`` | its elements | ``SPHERES_PER_ELEMENT`` spheres fitted to it (:mod:`sphere_fit`) | as they are |
| ``primitive`` | its elements | the enclosing capsule or oriented box, whichever has less volume | as they are |
| ``convex`` | its elements | its convex hull (``fcl.Convex``) | as they are |
| ``mesh`` | its elements | its triangles (``fcl.BVHModel``, OBBRSS tree; hull for depth) | as they are |
| ``auto`` | its elements | its hull if within ``AUTO_HULL_TOLERANCE`` of the mesh, else its triangles | as they are |

Every approximation encloses the exact geometry, so a coarser level can report contact early but never late. Self-
collision is the exception: the coarse levels (``COARSE_LEVELS``) report it only where ``convex``'s shapes touch
too, since their own shapes overlap around the joints in poses where the links are apart.
``auto`` is ``mesh`` to within the tolerance at ``convex``'s cost for the elements that are convex already: the
hull lies outside the mesh, so the distance to it is short of the distance to the mesh by at most the largest gap
between the two surfaces.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import fcl
import numpy as np
import trimesh
from scipy.spatial import QhullError

from clutter_gym.collision.sphere_fit import fit_spheres
from clutter_gym.urdf.geometry import CollisionElement
from clutter_gym.util.transforms import quat_to_matrix

FIDELITY_LEVELS = ("sphere", "spheres", "primitive", "convex", "mesh", "auto")
#: Levels whose shapes reach so far beyond the links that neighbouring links' shapes overlap in poses where the links
#: are apart: their self-collision hits are confirmed with ``CONFIRM_LEVEL``'s shapes (:mod:`confirm`), and they
#: check that level's ACM.
COARSE_LEVELS = ("sphere", "spheres", "primitive")
CONFIRM_LEVEL = "convex"
#: Spheres fitted to each mesh element at the ``spheres`` level.
SPHERES_PER_ELEMENT = 16
#: ``auto`` keeps a mesh element's triangles when its convex hull strays further than this from it, metres.
AUTO_HULL_TOLERANCE = 5e-4
#: Points sampled on a hull's surface to measure its gap to the mesh (plus every hull vertex).
HULL_GAP_SAMPLES = 1000


@dataclass(frozen=True, eq=False)
class LinkShape:
    """One FCL shape of a link, placed in the link frame.

    Attributes:
        link: URDF link name.
        geometry: the FCL shape in its own frame (cylinders and capsules along z, centred).
        position: (3,) shape origin in the link frame, metres.
        rotation: (3, 3) shape orientation in the link frame.
        kind: "sphere", "box", "cylinder", "capsule", "convex" or "mesh".
        radius: radius of a ball about the shape origin that encloses the shape, metres (bounds its rotation).
        ball: (centre (3,) in the shape frame, radius) of a tighter enclosing ball, for distance bounds; None
            for the ball about the origin.
        hull: for a ``mesh`` shape, its convex hull (``fcl.Convex``), used where FCL's triangle BVH gives no
            answer: penetration depth (its signed distance returns 0 or -1 on overlap), contact depth and swept
            checks (the sweep's advancement needs a convex shape). None otherwise.
    """

    link: str
    geometry: fcl.CollisionGeometry
    position: np.ndarray
    rotation: np.ndarray
    kind: str
    radius: float
    hull: fcl.CollisionGeometry | None = None
    ball: tuple[np.ndarray, float] | None = None

    @property
    def bounding_ball(self) -> tuple[np.ndarray, float]:
        """(centre in the shape frame, radius) of the tightest enclosing ball this shape knows."""
        return self.ball if self.ball is not None else (np.zeros(3), self.radius)


def check_fidelity(fidelity: str) -> str:
    if fidelity not in FIDELITY_LEVELS:
        raise ValueError(f"collision_fidelity must be one of {FIDELITY_LEVELS}, got {fidelity!r}")
    return fidelity


def build_link_shapes(elements: Sequence[CollisionElement], fidelity: str,
                      n_spheres: int = SPHERES_PER_ELEMENT) -> list[LinkShape]:
    """FCL shapes of ``elements`` at ``fidelity`` (one per element, one sphere per link, or at ``spheres``
    ``n_spheres`` per mesh element)."""
    check_fidelity(fidelity)
    if fidelity == "sphere":
        links = dict.fromkeys(e.link for e in elements)
        return [_link_sphere(link, [e for e in elements if e.link == link]) for link in links]
    if fidelity == "spheres":
        return [shape for e in elements for shape in _fitted_spheres(e, n_spheres)]
    return [_element_shape(e, fidelity) for e in elements]


def _fitted_spheres(e: CollisionElement, n: int) -> list[LinkShape]:
    """``n`` spheres fitted to a mesh element (at most), placed in the link frame; a primitive as it is."""
    if e.kind != "mesh":
        return [_element_shape(e, "convex")]
    centres, radii = _fit(*_content(e.mesh), n)
    positions = e.position + centres @ quat_to_matrix(e.quaternion).T
    return [LinkShape(e.link, fcl.Sphere(float(r)), p, np.eye(3), "sphere", float(r)) for p, r in zip(positions, radii)]


@functools.lru_cache(maxsize=256)
def _fit(vertices: bytes, faces: bytes, n: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`fit_spheres` cached by the mesh's content."""
    return fit_spheres(_mesh(vertices, faces), n)


def _content(mesh: trimesh.Trimesh) -> tuple[bytes, bytes]:
    """A mesh's vertices and faces as bytes: a cache key that holds the mesh (:func:`_mesh` rebuilds it)."""
    return np.asarray(mesh.vertices, dtype=float).tobytes(), np.asarray(mesh.faces, dtype=np.int64).tobytes()


def _mesh(vertices: bytes, faces: bytes) -> trimesh.Trimesh:
    return trimesh.Trimesh(np.frombuffer(vertices).reshape(-1, 3), np.frombuffer(faces, dtype=np.int64).reshape(-1, 3),
                           process=False)


def _element_shape(e: CollisionElement, fidelity: str) -> LinkShape:
    rotation = quat_to_matrix(e.quaternion)
    if e.kind != "mesh":
        return LinkShape(e.link, _primitive(e.kind, e.size), e.position, rotation, e.kind,
                         _primitive_radius(e.kind, e.size))
    vertices = np.asarray(e.mesh.vertices)
    vertices_radius = float(np.linalg.norm(vertices, axis=1).max())
    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))  # a mesh's origin is often far from its middle
    ball = (centre, float(np.linalg.norm(vertices - centre, axis=1).max()))
    if fidelity == "auto":
        fidelity = "mesh" if hull_gap(e.mesh) > AUTO_HULL_TOLERANCE else "convex"
    if fidelity == "mesh":
        return LinkShape(e.link, bvh_model(e.mesh), e.position, rotation, "mesh", vertices_radius, convex(e.mesh),
                         ball)
    if fidelity == "convex":
        return LinkShape(e.link, convex(e.mesh), e.position, rotation, "convex", vertices_radius, ball=ball)
    kind, size, local_position, local_rotation = fitted_primitive(e.mesh.convex_hull.vertices)
    return LinkShape(e.link, _primitive(kind, size), e.position + rotation @ local_position, rotation @ local_rotation,
                     kind, _primitive_radius(kind, size))


def _primitive_radius(kind: str, size: tuple[float, ...]) -> float:
    if kind == "box":
        return 0.5 * float(np.linalg.norm(size))
    if kind == "cylinder":
        return float(np.hypot(size[0], 0.5 * size[1]))
    if kind == "capsule":
        return size[0] + 0.5 * size[1]
    return size[0]


def _primitive(kind: str, size: tuple[float, ...]) -> fcl.CollisionGeometry:
    if kind == "box":
        return fcl.Box(*size)
    if kind == "cylinder":
        return fcl.Cylinder(*size)
    if kind == "capsule":
        return fcl.Capsule(*size)
    return fcl.Sphere(size[0])


def bvh_model(mesh: trimesh.Trimesh) -> fcl.BVHModel:
    """Triangle BVH of ``mesh`` (a surface: an object wholly inside it is not in contact)."""
    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int32))
    model.endModel()
    return model


def convex(mesh: trimesh.Trimesh) -> fcl.Convex:
    """``fcl.Convex`` of the convex hull of ``mesh``."""
    hull = mesh.convex_hull
    faces = np.hstack([np.full((len(hull.faces), 1), 3), hull.faces]).ravel()
    return fcl.Convex(np.asarray(hull.vertices, dtype=float), len(hull.faces), faces)


def hull_gap(mesh: trimesh.Trimesh) -> float:
    """The largest distance, in metres, from a point of ``mesh``'s convex hull to ``mesh`` itself (0 for a convex
    mesh), over every hull vertex and ``HULL_GAP_SAMPLES`` seeded points on the hull's faces. Cached by content."""
    return _hull_gap(*_content(mesh))


@functools.lru_cache(maxsize=64)
def _hull_gap(vertices: bytes, faces: bytes) -> float:
    mesh = _mesh(vertices, faces)
    hull = mesh.convex_hull
    samples, _ = trimesh.sample.sample_surface(hull, HULL_GAP_SAMPLES, seed=0)
    surface = fcl.CollisionObject(bvh_model(mesh), fcl.Transform())
    probe = fcl.CollisionObject(fcl.Sphere(1e-9), fcl.Transform())
    request, gap = fcl.DistanceRequest(), 0.0
    for point in np.vstack([hull.vertices, samples]):
        probe.setTranslation(point)
        gap = max(gap, fcl.distance(probe, surface, request, fcl.DistanceResult()))
    return float(gap)


def fitted_primitive(points: np.ndarray) -> tuple[str, tuple[float, ...], np.ndarray, np.ndarray]:
    """The smaller (by volume) of the capsule and the oriented box that enclose ``points``.

    The capsule's axis is the points' principal axis (largest variance); its radius is the largest distance
    from that axis, and its segment is the shortest one that keeps every point within that radius. The box is
    trimesh's minimum-volume oriented bounding box.

    Returns:
        kind ("capsule" or "box"), size ((radius, length) or full extents), and the shape's position (3,) and
        rotation (3, 3) in the points' frame (capsule axis = rotation's z column).
    """
    points = np.asarray(points, dtype=float)
    mean = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - mean, full_matrices=False)
    axis = vt[0]
    rel = points - mean
    t = rel @ axis
    radial = np.linalg.norm(rel - t[:, None] * axis, axis=1)
    radius = float(radial.max())
    reach = np.sqrt(np.maximum(radius**2 - radial**2, 0.0))
    a, b = float(np.min(t + reach)), float(np.max(t - reach))  # segment [a, b] along the axis
    if a > b:
        a = b = 0.5 * (a + b)
    capsule_volume = np.pi * radius**2 * (b - a) + 4.0 / 3.0 * np.pi * radius**3
    to_origin, extents = trimesh.bounds.oriented_bounds(points)
    box_volume = float(np.prod(extents))
    if box_volume <= capsule_volume:
        box_pose = np.linalg.inv(to_origin)
        return "box", tuple(extents.tolist()), box_pose[:3, 3], box_pose[:3, :3]
    rotation = _frame_with_z(axis)
    length = b - a
    if length <= 0.0:  # points fit in a ball: a capsule of zero length is a sphere
        return "sphere", (radius,), mean + a * axis, np.eye(3)  # points fit in a ball
    return "capsule", (radius, length), mean + 0.5 * (a + b) * axis, rotation


def _frame_with_z(axis: np.ndarray) -> np.ndarray:
    """A rotation whose z column is ``axis`` (unit)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = helper - (helper @ axis) * axis
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def _link_sphere(link: str, elements: Sequence[CollisionElement]) -> LinkShape:
    """The sphere about the elements' points' minimum enclosing ball centre that encloses every element exactly (about
    their bounding box's centre where Qhull cannot find that ball)."""
    samples, farthest = [], []
    for e in elements:
        r = quat_to_matrix(e.quaternion)
        samples.append(e.position + _surface_points(e) @ r.T)
        farthest.append(_farthest_distance_fn(e, r))
    points = np.vstack(samples)
    try:
        centre, _ = trimesh.nsphere.minimum_nsphere(points)
    except QhullError:  # a nearly flat set with many points on one circle: any centre gives an enclosing sphere
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    radius = max(f(centre) for f in farthest)
    return LinkShape(link, fcl.Sphere(float(radius)), np.asarray(centre, dtype=float), np.eye(3), "sphere",
                     float(radius))


def _surface_points(e: CollisionElement) -> np.ndarray:
    """Points on the element's surface in its own frame (used only to centre the link sphere)."""
    if e.kind == "mesh":
        return np.asarray(e.mesh.convex_hull.vertices)
    if e.kind == "box":
        return 0.5 * np.array(e.size) * np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
    a = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    ring = np.c_[np.cos(a), np.sin(a), np.zeros_like(a)]
    if e.kind == "sphere":
        return e.size[0] * np.vstack([ring, ring[:, [0, 2, 1]], ring[:, [2, 0, 1]]])
    radius, half = e.size[0], 0.5 * e.size[1]
    cap = radius if e.kind == "capsule" else 0.0
    return np.vstack([radius * ring + [0, 0, half], radius * ring - [0, 0, half], [[0, 0, half + cap]],
                      [[0, 0, -half - cap]]])


def _farthest_distance_fn(e: CollisionElement, r: np.ndarray):
    """A function of a point c (link frame) giving the largest distance from c to the element, exactly."""
    if e.kind == "mesh":
        vertices = e.position + np.asarray(e.mesh.convex_hull.vertices) @ r.T
        return lambda c: float(np.linalg.norm(vertices - c, axis=1).max())
    if e.kind in ("box", "sphere"):
        if e.kind == "sphere":
            return lambda c: float(np.linalg.norm(e.position - c)) + e.size[0]
        corners = e.position + _surface_points(e) @ r.T
        return lambda c: float(np.linalg.norm(corners - c, axis=1).max())
    radius, half, axis = e.size[0], 0.5 * e.size[1], r[:, 2]

    def farthest(c: np.ndarray) -> float:
        best = 0.0
        for end in (e.position + half * axis, e.position - half * axis):
            d = end - c
            axial = d @ axis
            perp = float(np.linalg.norm(d - axial * axis))
            best = max(best, float(np.linalg.norm(d)) + radius if e.kind == "capsule"
                       else np.hypot(axial, perp + radius))
        return best

    return farthest
