"""Ray casts of a :class:`~clutter_gym.sim.Sim`: pybullet's ``rayTestBatch`` or the exact caster over its primitives.

A part of :class:`clutter_gym.sim.Sim` (``sim.rays``) on the Sim's :class:`~clutter_gym.sim.world_record.WorldRecord`:
its client id, body and filter records and :class:`~clutter_gym.sim.primitives.PrimitiveTable`. The exact caster
(:func:`~clutter_gym.sim.ray_casting.cast_rays`) answers only while it models everything a ray can hit: the ground
plane and the boxes and cylinders made here. A world that holds anything else a ray can see (a URDF not hidden from
rays, a mesh, a body made with raw pybullet calls) is cast by pybullet.
"""

from __future__ import annotations

import operator

import numpy as np
import pybullet as pb

from clutter_gym.sim.ray_casting import cast_rays
from clutter_gym.sim.world_record import WorldRecord

#: Collision-filter group of bodies that rays do not report (the robot: a LIDAR never sees its own chassis).
#: pybullet applies the ray mask after the narrow phase, so this is about correctness, not speed.
RAY_INVISIBLE_GROUP = 4
_RAY_MASK = -1 ^ RAY_INVISIBLE_GROUP
_HIT_FRACTION = operator.itemgetter(2)  # field 2 of a rayTestBatch result row
MAX_RAY_BATCH = 16383  # rays one rayTestBatch call answers (16,384 silently return nothing, more raise)
#: Values of ``caster``: the exact caster where it models the world (else pybullet), or always pybullet.
RAY_CASTERS = ("exact", "pybullet")
_ORIGIN, _AXES = np.zeros(3), np.eye(3)


def link_frame(cid: int, body: int, link: int) -> tuple[np.ndarray, np.ndarray]:
    """(origin (3,), rotation (3, 3)) of a link's URDF frame in world coordinates, in client ``cid``, rebuilt from the
    link's centre of mass and its inertial offset as ``Sim.link_states`` does: pybullet's own link frame is rounded
    to float32. Rays given in a link's frame are cast from it; the Sim's ``link_frame`` is this."""
    com, com_quat, offset, offset_quat = pb.getLinkState(body, link, physicsClientId=cid)[:4]
    rotation = np.array(pb.getMatrixFromQuaternion(com_quat, physicsClientId=cid)).reshape(3, 3)
    if offset_quat != (0.0, 0.0, 0.0, 1.0):  # the inertial frame's axes in the link frame
        rotation = rotation @ np.array(pb.getMatrixFromQuaternion(offset_quat)).reshape(3, 3).T
    return np.array(com) - rotation @ np.array(offset), rotation


class Rays:
    """Batched ray casts of one Sim's world, on the Sim's world record (it holds no reference to the Sim, so a
    dropped Sim is freed, and its client disconnected, by reference counting)."""

    def __init__(self, record: WorldRecord) -> None:
        self._record = record
        self._exact_rays_key: tuple[int, int] | None = None  # (record version, pybullet's body count) last checked
        self._exact_rays = False

    def ray_hit_fractions(
        self, starts: list | np.ndarray, ends: list | np.ndarray, body: int = -1, link: int = -1,
        caster: str = "pybullet",
    ) -> np.ndarray:
        """Cast a batch of rays; returns the hit fraction per ray (1.0 = no hit).

        Args:
            starts, ends: (n, 3) metres. pybullet converts a ready nested list faster than an ndarray, but an
                ndarray made this step is faster to pass as it is than through ``tolist()``
                (docs/design-notes.md#ray-lists).
            body, link: when ``body`` >= 0 the rays are given in that link's frame (``link`` >= 0), which moves
                them with it, so a sensor can keep constant ray lists.
            caster: "pybullet" (``rayTestBatch``) or "exact" (:func:`~clutter_gym.sim.ray_casting.cast_rays` on the
                true boxes, cylinders and ground plane, while :meth:`exact_rays_model_world`; else pybullet). They
                differ on cylinders, which pybullet hits as 64-gon prisms (at most 0.53 mm;
                docs/speed-vs-error.md), and on a ray starting inside a cylinder (pybullet: its wall; exact: missed,
                as pybullet misses a box it starts in).

        Bodies hidden with :meth:`hide_from_rays` are not hit. More than :data:`MAX_RAY_BATCH` rays go in several
        ``rayTestBatch`` calls.

        Raises:
            ValueError: ``caster`` is not one of :data:`RAY_CASTERS`.
            RuntimeError: pybullet is to cast while some obstacles have no body (the primitives' backdrop): its
                rays would pass through them.
        """
        if caster not in RAY_CASTERS:
            raise ValueError(f"caster must be one of {RAY_CASTERS}, got {caster!r}")
        if caster == "exact" and (body < 0 or link >= 0) and self.exact_rays_model_world():
            origin, axes = link_frame(self._record.cid, body, link) if body >= 0 else (_ORIGIN, _AXES)
            return self.cast_exact(starts, ends, origin, axes)
        if self._record.primitives.backdrop_shown:
            raise RuntimeError("pybullet cannot cast these rays: a large scene keeps its far obstacles out of the "
                               "physics world (worlds/near_field.py), and the world holds bodies the exact caster does "
                               "not model; set env.unwrapped.arena.near_field = False before reset to keep every "
                               "obstacle a body")
        if len(starts) > MAX_RAY_BATCH:
            return np.concatenate([
                self.ray_hit_fractions(starts[i:i + MAX_RAY_BATCH], ends[i:i + MAX_RAY_BATCH], body, link)
                for i in range(0, len(starts), MAX_RAY_BATCH)
            ])
        hits = pb.rayTestBatch(
            starts, ends, parentObjectUniqueId=body, parentLinkIndex=link, numThreads=1,
            collisionFilterMask=_RAY_MASK, physicsClientId=self._record.cid,
        )
        return np.fromiter(map(_HIT_FRACTION, hits), dtype=float, count=len(hits))

    def cast_exact(self, starts: list | np.ndarray, ends: list | np.ndarray, origin: np.ndarray | None = None,
                   axes: np.ndarray | None = None) -> np.ndarray:
        """Hit fractions of the exact caster (see :meth:`ray_hit_fractions`) for rays given in the frame at ``origin``
        (3,) with ``axes`` (3, 3, as columns; default: the world frame), whatever else the world holds: check
        :meth:`exact_rays_model_world` first."""
        starts, ends = np.asarray(starts, dtype=float), np.asarray(ends, dtype=float)
        _, kinds, centres, rotations, halves = self._record.primitives.solids()
        fractions = np.empty(len(starts))
        cast_rays(_ORIGIN if origin is None else origin, _AXES if axes is None else axes, starts, ends, kinds, centres,
                  rotations, halves, self._record.ground >= 0, fractions)
        return fractions

    def exact_rays_model_world(self) -> bool:
        """Whether the exact caster sees everything pybullet's rays would: every body is the ground, a box or
        cylinder of the record's primitives, a marker (no collision shape) or hidden from rays. Answered again only
        after the world changed (a body made, loaded, removed or hidden through the Sim, or by raw pybullet calls)."""
        record = self._record
        key = (record.version, pb.getNumBodies(physicsClientId=record.cid))
        if self._exact_rays_key != key:
            known = record.body_ids | {pb.getBodyUniqueId(i, physicsClientId=record.cid) for i in range(key[1])}
            self._exact_rays = all(
                b in record.primitives or record.filters.get(b, (0, 0))[0] == RAY_INVISIBLE_GROUP for b in known
            )
            self._exact_rays_key = key
        return self._exact_rays

    def hide_from_rays(self, body: int) -> None:
        """Put every link of ``body`` in :data:`RAY_INVISIBLE_GROUP`: rays pass through it, contacts do not.

        Bullet's default masks (all bits for dynamic bodies, all but the static bit for static ones) include this
        group, so contacts with the ground and obstacles are unchanged.
        """
        self._record.filters[body] = (RAY_INVISIBLE_GROUP, -1)
        self._record.version += 1
        self._record.apply_filter(body)
