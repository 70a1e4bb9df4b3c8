"""Obstacle bodies: static boxes and cylinders made in batches, movable ones with a mass, and the pool's moves.

A part of :class:`clutter_gym.sim.Sim` (``sim.obstacles``) on the Sim's
:class:`~clutter_gym.sim.world_record.WorldRecord`: its client id and its body, shape and filter records. Every
body here is a plain (maximal-coordinate) rigid body, cheaper each physics tick than a multibody.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pybullet as pb

from clutter_gym.sim.world_record import WorldRecord
from clutter_gym.util.meshes import prism_mesh

CYLINDER_SIDES = 64
_UNIT_PRISM = prism_mesh(1.0, 1.0, CYLINDER_SIDES)
_DYNAMIC_GROUP = 1  # Bullet's collision group of dynamic bodies
#: Bodies one ``createMultiBody(batchPositions=...)`` call makes. pybullet passes the positions in its data stream,
#: 1 MiB on macOS (8 MiB elsewhere), and silently cuts a longer list short (24 bytes a body).
MAX_BODY_BATCH = 4096
#: The collision filter Bullet gives a static body: it meets every group but other static bodies.
_STATIC_GROUP = 2
_STATIC_MASK = -1 ^ _STATIC_GROUP


class ObstacleBodies:
    """Making, moving, hiding and removing the obstacle bodies of one Sim's world."""

    def __init__(self, record: WorldRecord) -> None:
        self._record = record

    def add_static_boxes(
        self, half_extents: Sequence[float], rgba: Sequence[float], positions: Sequence[Sequence[float]]
    ) -> list[int]:
        """Add static (mass 0) boxes of one size and colour, one centred at each of ``positions`` (metres, world
        frame) and unrotated (turn them with :meth:`move_static`); returns their body ids in that order.

        Bodies of one size and colour share their shapes: pybullet could not free a second copy.

        Args:
            half_extents: half sizes along x, y and z in metres.
            rgba: colour, each channel in [0, 1].
            positions: centres, one per box.
        """
        shapes = self._box_shapes(half_extents, rgba)
        bodies = self.static_bodies(*shapes, positions, float(np.linalg.norm(half_extents)), rgba)
        for body, position in zip(bodies, positions):
            self._record.primitives.add(body, "box", half_extents, position)
        return bodies

    def _box_shapes(self, half_extents: Sequence[float], rgba: Sequence[float]) -> tuple[int, int]:
        """(collision, visual) shape ids of a box, made once per size and colour; static and movable boxes share
        them."""
        key = ("box", tuple(map(float, half_extents)), tuple(rgba))
        if key not in self._record.shapes:
            self._record.shapes[key] = (
                pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half_extents, physicsClientId=self._record.cid),
                self._visual_shape(pb.GEOM_BOX, halfExtents=half_extents, rgbaColor=rgba),
            )
        return self._record.shapes[key]

    def add_static_cylinders(
        self, radius: float, height: float, rgba: Sequence[float], positions: Sequence[Sequence[float]]
    ) -> list[int]:
        """Add static (mass 0) upright cylinders of one size and colour, like :meth:`add_static_boxes`.

        Their collision shape is a concave triangle mesh of a ``CYLINDER_SIDES``-gon prism with the circle's area,
        not Bullet's cylinder primitive: rays against the primitive go through GJK convex casting, which is slow and
        still inexact, while the prism is hit by BVH ray-triangle tests, faster and with sub-millimetre error
        (docs/design-notes.md#cylinders). The visual shape stays a true cylinder. The mesh has no collision margin:
        pybullet's default margin makes contacts fire before FCL's exact cylinder touches
        (docs/design-notes.md#mesh-collision-margin).

        Args:
            radius: radius in metres.
            height: height in metres.
            rgba: colour, each channel in [0, 1].
            positions: centres, one per cylinder.
        """
        key = ("cylinder", (float(radius), float(height)), tuple(rgba))
        if key not in self._record.shapes:
            vertices, indices = _UNIT_PRISM  # one shared list: pybullet keeps a reference to every list it is given
            self._record.shapes[key] = (
                pb.createCollisionShape(
                    pb.GEOM_MESH,
                    vertices=vertices,
                    indices=indices,
                    meshScale=[radius, radius, height],
                    flags=pb.GEOM_FORCE_CONCAVE_TRIMESH,
                    physicsClientId=self._record.cid,
                ),
                self._visual_shape(pb.GEOM_CYLINDER, radius=radius, length=height, rgbaColor=rgba),
            )
        bodies = self.static_bodies(*self._record.shapes[key], positions, float(np.hypot(radius, 0.5 * height)), rgba)
        for body, position in zip(bodies, positions):
            pb.changeDynamics(body, -1, collisionMargin=0.0, physicsClientId=self._record.cid)
            self._record.primitives.add(body, "cylinder", (radius, radius, 0.5 * height), position)
        return bodies

    def add_movable_box(self, half_extents: Sequence[float], rgba: Sequence[float]) -> int:
        """Add a dynamic box centred at the origin, parked (mass 0) until :meth:`set_mass` gives it a mass; returns
        its body id. Shapes are shared like :meth:`add_static_boxes`'s."""
        body = self._movable_body(*self._box_shapes(half_extents, rgba), float(np.linalg.norm(half_extents)), rgba)
        self._record.primitives.add(body, "box", half_extents, (0.0, 0.0, 0.0))
        return body

    def add_movable_cylinder(self, radius: float, height: float, rgba: Sequence[float]) -> int:
        """Add a dynamic upright cylinder centred at the origin, like :meth:`add_movable_box`.

        Its collision shape is the convex hull of the prism :meth:`add_static_cylinders` uses (Bullet cannot move a
        concave triangle mesh), without collision margin, so rays and contacts see the same shape either way.
        """
        key = ("movable cylinder", (float(radius), float(height)), tuple(rgba))
        if key not in self._record.shapes:
            vertices, _ = _UNIT_PRISM
            self._record.shapes[key] = (
                pb.createCollisionShape(pb.GEOM_MESH, vertices=vertices, meshScale=[radius, radius, height],
                                        physicsClientId=self._record.cid),
                self._visual_shape(pb.GEOM_CYLINDER, radius=radius, length=height, rgbaColor=rgba),
            )
        body = self._movable_body(*self._record.shapes[key], float(np.hypot(radius, 0.5 * height)), rgba)
        pb.changeDynamics(body, -1, collisionMargin=0.0, physicsClientId=self._record.cid)
        self._record.primitives.add(body, "cylinder", (radius, radius, 0.5 * height), (0.0, 0.0, 0.0))
        return body

    def _movable_body(self, collision: int, visual: int, radius: float, rgba: Sequence[float]) -> int:
        """A rigid body made with a mass, so that it is dynamic (a body made with mass 0 stays static for good),
        then parked at mass 0; its collision filter is recorded so that ``WorldRecord.forget_contacts`` can reset it.
        One call each, which returns the true id whatever removed ids wait for reuse."""
        body = pb.createMultiBody(1.0, collision, visual, useMaximalCoordinates=True, physicsClientId=self._record.cid)
        pb.changeDynamics(body, -1, mass=0.0, physicsClientId=self._record.cid)
        self._record.made([body])
        self._record.filters[body] = (_DYNAMIC_GROUP, -1)
        if self._record.visuals:
            self._record.culler.add(body, radius, tuple(np.asarray(rgba, dtype=np.float32).tolist()))
        return body

    def set_mass(self, body: int, mass: float, inertia: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Give a body made by :meth:`add_movable_box` or :meth:`add_movable_cylinder` its mass (kg) and principal
        moments of inertia (kg m^2, about its centre); mass 0 holds it where it is. Its velocity is zeroed and its
        contact history forgotten, so that a body placed again starts as if new (same seed, same trajectory). It falls
        asleep once it has rested a while, as Bullet's bodies can (pybullet turns that off by default): a resting
        body then stays exactly where it is until something touches it."""
        pb.changeDynamics(body, -1, mass=mass, localInertiaDiagonal=inertia,
                          activationState=pb.ACTIVATION_STATE_ENABLE_SLEEPING, physicsClientId=self._record.cid)
        pb.resetBaseVelocity(body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), physicsClientId=self._record.cid)
        self._record.forget_contacts(body)

    def body_poses(self, bodies: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """(n, 3) positions (metres) and (n, 3, 3) rotation matrices of ``bodies``' base frames; the view culler
        follows them (call it after the physics moved them)."""
        poses = [pb.getBasePositionAndOrientation(b, physicsClientId=self._record.cid) for b in bodies]
        positions = np.array([p for p, _ in poses], dtype=float).reshape(-1, 3)
        rotations = np.array([pb.getMatrixFromQuaternion(q) for _, q in poses], dtype=float).reshape(-1, 3, 3)
        for body, position, rotation in zip(bodies, positions, rotations):
            self._record.culler.move(body, position)
            self._record.primitives.move(body, position, rotation)
        return positions, rotations

    def _visual_shape(self, geometry: int, **kwargs) -> int:
        """A visual shape of an obstacle, or -1 (none) when the Sim has no visuals."""
        if not self._record.visuals:
            return -1
        return pb.createVisualShape(geometry, **kwargs, physicsClientId=self._record.cid)

    def static_bodies(
        self,
        collision: int,
        visual: int,
        positions: Sequence[Sequence[float]],
        radius: float | None = None,
        rgba: Sequence[float] = (),
    ) -> list[int]:
        """Add mass-0 bodies as plain (maximal-coordinate) rigid bodies, not Featherstone multibodies, one at each of
        ``positions``; returns their ids in that order.

        Every body in the world costs each physics tick, even fixed and far away, and a multibody costs more than a
        static rigid body, a sleeping one less again (docs/design-notes.md#static-bodies).

        Bodies are made up to :data:`MAX_BODY_BATCH` in one ``createMultiBody(batchPositions=...)`` call. After a
        call pybullet's server serialises a description of the body it made and its client parses it, most of what
        a call costs; a batch describes only its last body (docs/design-notes.md#batched-bodies). The client's list
        of bodies (``getNumBodies``) then misses the others: :attr:`WorldRecord.body_ids` keeps them. pybullet
        numbers a batch as if its ids were consecutive, which holds only while no removed id is left for it to reuse
        (it reuses those first), so until then bodies are made one call each, and each call returns its true id.

        Args:
            collision: collision shape id (-1: visual only).
            visual: visual shape id (-1: none).
            positions: base positions in metres, world frame.
            radius: radius in metres of a sphere about a body's origin that holds its visual. Bodies given one join
                the record's culler (when the Sim has visuals) and are culled from the camera frames they cannot
                appear in.
            rgba: the visual's colour, each channel in [0, 1] (needed with ``radius``).
        """
        positions = [[float(v) for v in p] for p in positions]
        bodies: list[int] = []
        while len(bodies) < len(positions):
            batch = positions[len(bodies):len(bodies) + MAX_BODY_BATCH]
            if self._record.freed:
                body = pb.createMultiBody(
                    0.0, collision, visual, batch[0], useMaximalCoordinates=True, physicsClientId=self._record.cid
                )
                self._record.freed.discard(body)
                bodies.append(body)
            else:
                bodies.extend(pb.createMultiBody(
                    0.0, collision, visual, useMaximalCoordinates=True, batchPositions=batch,
                    physicsClientId=self._record.cid,
                ))
        self._record.made(bodies)
        if radius is not None and self._record.visuals:
            colour = tuple(np.asarray(rgba, dtype=np.float32).tolist())  # as pybullet stores it: single precision
            for body, position in zip(bodies, positions):
                self._record.culler.add(body, radius, colour)
                self._record.culler.move(body, position)
        return bodies

    def order_broadphase(self, bodies: Sequence[int]) -> None:
        """Give the obstacle ``bodies`` new broad-phase entries, in this order, after those of every other body.

        Bullet solves a tick's contacts in the order of their bodies' broad-phase ids, which follow the order the
        bodies were made in: two obstacles a robot touches at once, made the other way round, give another
        trajectory. Bodies made in batches, one shape at a time, get here the order of their scene
        (docs/design-notes.md#batched-bodies). Their cached contacts go, as those of a body just made would.
        """
        for body in bodies:
            group, mask = self._record.filters.get(body, (_STATIC_GROUP, _STATIC_MASK))  # movable bodies keep their own
            pb.setCollisionFilterGroupMask(body, -1, group, mask, physicsClientId=self._record.cid)

    def remove_body(self, body: int) -> None:
        """Delete a body from the world (its collision and visual shapes stay cached for reuse)."""
        pb.removeBody(body, physicsClientId=self._record.cid)
        self._record.removed(body)

    def set_visible(self, body: int, visible: bool, rgba: Sequence[float]) -> None:
        """Show a single-shape body in colour ``rgba`` (channels in [0, 1]), or hide it from every renderer (fully
        transparent shapes are skipped by TinyRenderer: a parked obstacle then costs a camera frame nothing).

        Only the ray-cast camera's primitives are told in a Sim without visuals."""
        self._record.primitives.show(body, visible)
        if not self._record.visuals:
            return
        colour = (*rgba[:3], rgba[3] if visible else 0.0)
        pb.changeVisualShape(body, -1, rgbaColor=colour, physicsClientId=self._record.cid)
        self._record.culler.set_colour(body, colour)

    def sleep(self, body: int) -> None:
        """Deactivate a static body so the physics tick skips it (teleporting it wakes it again)."""
        pb.changeDynamics(body, -1, activationState=pb.ACTIVATION_STATE_SLEEP, physicsClientId=self._record.cid)

    def rotation_matrices(self, quaternions: Sequence[Sequence[float]]) -> np.ndarray:
        """(n, 3, 3) rotation matrices of ``quaternions`` (x, y, z, w) as :meth:`move_static` gives them to
        the record's primitives, bit for bit."""
        rows = [pb.getMatrixFromQuaternion(q, physicsClientId=self._record.cid) for q in quaternions]
        return np.array(rows, dtype=float).reshape(-1, 3, 3)

    def move_static(self, body: int, position: Sequence[float], quaternion: Sequence[float]) -> None:
        """Teleport a static body's base inertial frame to ``position`` (metres, world frame) and ``quaternion``
        (x, y, z, w); it has no velocity to reset."""
        pb.resetBasePositionAndOrientation(body, position, quaternion, physicsClientId=self._record.cid)
        self._record.culler.move(body, position)
        rotation = pb.getMatrixFromQuaternion(quaternion, physicsClientId=self._record.cid)
        self._record.primitives.move(body, position, rotation)
