"""A robot's FCL objects at one fidelity level, moved to its link poses, and its self-collision queries."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import fcl
import numpy as np

from clutter_gym.collision.acm import AllowedCollisionMatrix, load_acm
from clutter_gym.collision.confirm import PairConfirmer
from clutter_gym.collision.distance import signed_distance
from clutter_gym.collision.fidelity import COARSE_LEVELS, CONFIRM_LEVEL, LinkShape, build_link_shapes
from clutter_gym.urdf.geometry import load_collision_elements

#: Spheres from which a model's spheres are a sphere set: answered from their balls in numpy, placed in FCL only
#: when asked. A few spheres among other shapes (a base's casters) cost less answered one by one by FCL.
SPHERE_SET = 8


@dataclass(frozen=True, slots=True)
class SelfClearance:
    """Closest enabled pair of links: signed distance (metres, padding subtracted; negative = penetration)."""

    distance: float
    links: tuple[str, str] | None


class RobotCollisionModel:
    """FCL objects for every shape of a robot, placed at the link poses given to :meth:`sync`.

    Args:
        shapes: the robot's shapes at one fidelity level (see :func:`build_link_shapes`).
        link_names: names of the rows of the pose arrays passed to :meth:`sync`.
        padding: metres added around every link (a float), or per link name (missing links get 0), against the
            world: it is applied exactly, as a Minkowski sum with a ball, subtracted from every distance to an
            obstacle. Self-collision is checked on the unpadded shapes, as the ACM is sampled on them: neighbouring
            links sit a few centimetres apart in every pose, and padding them would put the robot in
            self-collision everywhere.
        acm: pairs of links whose self-collision is checked; None checks none.
        confirm_shapes: finer shapes of the same links (a coarse level's model gets the ``convex`` level's): a pair
            of links is in self-collision only when these touch too, and ``shapes`` serve as their broad phase
            (:mod:`confirm`). Where ``shapes`` enclose them (``sphere``, ``primitive``) the verdict is theirs;
            ``spheres``' sphere sets enclose the meshes, not their hulls, so it can miss a touch of the hulls alone.
            Empty: ``shapes`` decide.

    Raises:
        ValueError: a shape's link is not among ``link_names``, or a padding is negative or not finite.
    """

    def __init__(
        self,
        shapes: Sequence[LinkShape],
        link_names: Sequence[str],
        padding: float | Mapping[str, float] = 0.0,
        acm: AllowedCollisionMatrix | None = None,
        confirm_shapes: Sequence[LinkShape] = (),
    ) -> None:
        self.shapes = list(shapes)
        self.link_names = tuple(link_names)
        missing = sorted({s.link for s in self.shapes} - set(self.link_names))
        if missing:
            raise ValueError(f"links {missing} have collision shapes but no pose row; rows: {self.link_names}")
        self.links = tuple(dict.fromkeys(s.link for s in self.shapes))  # links with geometry, in shape order
        pad = padding if isinstance(padding, Mapping) else dict.fromkeys(self.links, padding)
        for link, value in pad.items():
            if not (np.isfinite(value) and 0.0 <= value <= 1.0):
                raise ValueError(f"padding for link {link!r} must be in [0, 1] metres, got {value!r}")
        self.padding = np.array([float(pad.get(s.link, 0.0)) for s in self.shapes])
        self._rows = np.array([self.link_names.index(s.link) for s in self.shapes])  # shape -> pose row
        self._local_pos = np.array([s.position for s in self.shapes])
        self._local_rot = np.array([s.rotation for s in self.shapes])
        ball_offset = np.array([s.bounding_ball[0] for s in self.shapes]).reshape(-1, 3)
        self._ball_offset = ball_offset if ball_offset.any() else None  # None: every ball is about its origin
        #: radius of every shape's enclosing ball (:meth:`ball_centres`), metres
        self.ball_radius = np.array([s.bounding_ball[1] for s in self.shapes])
        self.objects = [fcl.CollisionObject(s.geometry, fcl.Transform()) for s in self.shapes]
        # objects that answer depth and swept queries: the hull of a mesh shape, else the shape itself
        self.solid_objects = [
            fcl.CollisionObject(s.hull, fcl.Transform()) if s.hull is not None else o
            for s, o in zip(self.shapes, self.objects)
        ]
        self._hulls = [(o, h) for o, h in zip(self.objects, self.solid_objects) if o is not h]
        #: per shape: its enclosing ball is the shape itself (a sphere), so ball distances are its exact distances
        self.exact = np.array([s.kind == "sphere" and s.ball is None for s in self.shapes], dtype=bool)
        #: per shape: a sphere of a sphere set (at least ``SPHERE_SET`` spheres), answered in numpy from its ball;
        #: its FCL object is placed only when asked for (:meth:`object`), which most steps never do
        self.lazy = self.exact if self.exact.sum() >= SPHERE_SET else np.zeros(len(self.shapes), dtype=bool)
        self._eager = [(o, i) for i, o in enumerate(self.objects) if not self.lazy[i]]
        self._stale = [False] * len(self.shapes)  # objects not yet placed at the poses of the last set_poses
        self.position = np.zeros((len(self.shapes), 3))
        self.rotation = np.broadcast_to(np.eye(3), (len(self.shapes), 3, 3)).copy()
        self._collide_request = fcl.CollisionRequest()
        self._confirm = PairConfirmer(confirm_shapes, self.link_names) if confirm_shapes else None
        self.set_acm(acm)

    @classmethod
    def from_urdf(
        cls,
        urdf: str | Path,
        fidelity: str,
        link_names: Sequence[str],
        padding: float | Mapping[str, float] = 0.0,
        self_collision: bool = True,
    ) -> RobotCollisionModel:
        """The model of ``urdf`` at ``fidelity``, with its cached ACM when ``self_collision`` is on. At a coarse
        level (``COARSE_LEVELS``) that ACM is ``CONFIRM_LEVEL``'s and its self-collision hits are confirmed with
        that level's shapes: it checks the pairs that level checks and reports self-collision only where that level
        does, instead of where its own shapes overlap and the links do not."""
        elements = load_collision_elements(urdf)
        shapes = build_link_shapes(elements, fidelity)
        if not self_collision:
            return cls(shapes, link_names, padding)
        acm = load_acm(urdf, fidelity)
        confirm = build_link_shapes(elements, CONFIRM_LEVEL) if fidelity in COARSE_LEVELS and acm.enabled else ()
        return cls(shapes, link_names, padding, acm, confirm)

    def set_acm(self, acm: AllowedCollisionMatrix | None) -> None:
        """Check self-collision for the pairs ``acm`` enables (shape pairs of those link pairs)."""
        self.acm = acm
        enabled = set(acm.enabled) if acm is not None else set()
        self.self_pairs = [
            (i, j)
            for i in range(len(self.shapes))
            for j in range(i + 1, len(self.shapes))
            if tuple(sorted((self.shapes[i].link, self.shapes[j].link))) in enabled
        ]
        self._self_links = [(self.shapes[i].link, self.shapes[j].link) for i, j in self.self_pairs]
        first, second = np.array(self.self_pairs, dtype=int).reshape(-1, 2).T
        radius = self.ball_radius  # self pairs are unpadded (see padding above)
        self._pair_index = (first, second, radius[first] + radius[second])
        spheres = self.exact[first] & self.exact[second]  # pairs of spheres: their ball bounds are their distances
        self._sphere_pairs, self._other_pairs = np.flatnonzero(spheres), np.flatnonzero(~spheres)

    def _pair_bounds(self) -> np.ndarray:
        """Lower bounds on every enabled pair's (unpadded) distance, from the shapes' bounding balls."""
        first, second, reach = self._pair_index
        centres = self.ball_centres()
        return np.linalg.norm(centres[first] - centres[second], axis=1) - reach

    def world_poses(self, positions: np.ndarray, rotations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions (n, 3) and rotations (n, 3, 3) of every shape for link poses given by row."""
        rot = rotations[self._rows]
        return positions[self._rows] + np.einsum("nij,nj->ni", rot, self._local_pos), rot @ self._local_rot

    def sync(self, positions: np.ndarray, rotations: np.ndarray) -> None:
        """Move every FCL object to its link's pose (``positions`` (L, 3), ``rotations`` (L, 3, 3) by row)."""
        self.position, self.rotation = self.world_poses(positions, rotations)
        self._stale = [False] * len(self.shapes)
        if self._confirm is not None:
            self._confirm.set_link_poses(positions, rotations)
        rotation, position = self.rotation, self.position
        for obj, i in self._eager:
            obj.setRotation(rotation[i])
            obj.setTranslation(position[i])
        for obj, hull in self._hulls:
            hull.setTransform(obj.getTransform())

    def set_poses(self, positions: np.ndarray, rotations: np.ndarray) -> None:
        """:meth:`sync`, except that each FCL object is moved only when :meth:`object` or :meth:`solid_object` first
        asks for it: a query that measures a few shapes moves only those (:attr:`objects` may be out of date)."""
        self.position, self.rotation = self.world_poses(positions, rotations)
        self._stale = [True] * len(self.shapes)
        if self._confirm is not None:
            self._confirm.set_link_poses(positions, rotations)

    def object(self, i: int) -> fcl.CollisionObject:
        """Shape ``i``'s FCL object at the synced pose."""
        obj = self.objects[i]
        if self.lazy[i]:
            obj.setTranslation(self.position[i])
        elif self._stale[i]:
            obj.setRotation(self.rotation[i])
            obj.setTranslation(self.position[i])
            if self.solid_objects[i] is not obj:
                self.solid_objects[i].setTransform(obj.getTransform())
            self._stale[i] = False
        return obj

    def solid_object(self, i: int) -> fcl.CollisionObject:
        """Shape ``i``'s object for depth and swept queries (a mesh's hull) at the synced pose."""
        obj = self.object(i)
        return obj if self.lazy[i] else self.solid_objects[i]

    def ball_centres(self) -> np.ndarray:
        """(n, 3) world centres of the shapes' enclosing balls (radii :attr:`ball_radius`) at the synced poses."""
        return self.ball_centres_at(self.position, self.rotation)

    def bounding_ball(self) -> tuple[np.ndarray, float]:
        """(centre (3,), radius) of a ball holding every shape at the synced poses, padding included, metres: about
        the middle of the shapes' enclosing balls."""
        centres = self.ball_centres()
        middle = 0.5 * (centres.min(axis=0) + centres.max(axis=0))
        gaps = centres - middle
        return middle, float((np.sqrt((gaps * gaps).sum(axis=1)) + self.ball_radius + self.padding).max())

    def link_radii(self) -> dict[str, float]:
        """Per link with geometry: the farthest point of its shapes (their enclosing balls, padding included) from the
        link frame's origin, metres."""
        offsets = self._ball_offset if self._ball_offset is not None else np.zeros_like(self._local_pos)
        centres = self._local_pos + np.einsum("nij,nj->ni", self._local_rot, offsets)
        reach = np.linalg.norm(centres, axis=1) + self.ball_radius + self.padding
        radii: dict[str, float] = {}
        for shape, value in zip(self.shapes, reach):
            radii[shape.link] = max(radii.get(shape.link, 0.0), float(value))
        return radii

    def ball_centres_at(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """(n, 3) world centres of the shapes' enclosing balls with the shapes at ``position`` (n, 3) and
        ``rotation`` (n, 3, 3)."""
        if self._ball_offset is None:
            return position
        return position + np.einsum("nij,nj->ni", rotation, self._ball_offset)

    def self_collision(self) -> tuple[str, str] | None:
        """The first enabled link pair in collision (unpadded shapes), or None. With ``confirm_shapes``, the
        first whose confirming shapes touch too; a pair they reject is not asked about again in this call."""
        if not self.self_pairs:
            return None
        request, exact, confirm = self._collide_request, self.exact, self._confirm
        rejected: set[tuple[str, str]] = set()
        for k in np.flatnonzero(self._pair_bounds() <= 0.0):  # pairs whose balls are apart cannot touch
            i, j = self.self_pairs[k]
            links = self._self_links[k]
            if links in rejected:
                continue
            if exact[i] and exact[j]:  # two spheres: overlapping balls are the collision
                hit = True
            else:
                hit = fcl.collide(self.object(i), self.object(j), request, fcl.CollisionResult()) > 0
            if hit:
                if confirm is None or confirm.collide(*links):
                    return links
                rejected.add(links)
        return None

    def self_clearance(self) -> SelfClearance:
        """Smallest signed distance over the enabled link pairs, and that pair, measured on this model's own shapes
        (never on ``confirm_shapes``): at a coarse level it may be negative where :meth:`self_collision` finds no
        pair in collision."""
        best, pair = np.inf, None
        bounds = self._pair_bounds()
        spheres, others = self._sphere_pairs, self._other_pairs
        if len(spheres):
            k = int(spheres[np.argmin(bounds[spheres])])
            i, j = self.self_pairs[k]
            best, pair = float(bounds[k]), (self.shapes[i].link, self.shapes[j].link)
        for k in others[np.argsort(bounds[others], kind="stable")]:
            if bounds[k] >= best:
                break
            i, j = self.self_pairs[k]
            d = self._pair_distance(i, j)
            if d < best:
                best, pair = d, (self.shapes[i].link, self.shapes[j].link)
        return SelfClearance(float(best), pair)

    def _pair_distance(self, i: int, j: int) -> float:
        d, _ = signed_distance(self.object(i), self.object(j))
        if d <= 0.0:  # overlap: the depth comes from the solid shapes (a BVH has none)
            d, _ = signed_distance(self.solid_object(i), self.solid_object(j))
        return d
