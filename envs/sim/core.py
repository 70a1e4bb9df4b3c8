""":class:`Sim`: one pybullet physics client, its world and robots, and the batched reads of the hot path.

Robot actuation (``sim.actuation``: :mod:`clutter_gym.sim.actuation`), obstacle bodies (``sim.obstacles``:
:mod:`clutter_gym.sim.obstacles`), ray casts (``sim.rays``: :mod:`clutter_gym.sim.rays`) and camera images
(``sim.rendering``: :mod:`clutter_gym.sim.rendering`) are its parts, objects that each take the one state they share,
the :class:`~clutter_gym.sim.world_record.WorldRecord` of what was made in the world.
"""

from __future__ import annotations

import contextlib
import weakref
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pybullet as pb  # imported quietly by the package first

from clutter_gym.datatypes import LinkStates
from clutter_gym.sim.actuation import Actuation
from clutter_gym.sim.obstacles import ObstacleBodies
from clutter_gym.sim.primitives import PrimitiveTable
from clutter_gym.sim.rays import Rays, link_frame
from clutter_gym.sim.rendering import Rendering
from clutter_gym.sim.world_record import WorldRecord
from clutter_gym.util.quiet import quiet_c_output
from clutter_gym.util.view_culling import ViewCuller

#: pybullet frees no shape a body has used (``removeCollisionShape`` then frees nothing) and keeps about a
#: kilobyte of every removed body; only ``resetSimulation`` gives the memory back (docs/design-notes.md#memory).
#: Past either limit :attr:`Sim.needs_rebuild` turns true, and the env rebuilds its world on the next reset.
#: m/s^2, the standard gravity the world, the IMU's model of it and the flyer's hover thrust all take
GRAVITY = 9.81
MAX_SHAPES = 256
MAX_REMOVED_BODIES = 2_000


def _disconnect(client: int) -> None:
    """Disconnect a pybullet client (the GUI prints its thread shutdown: silenced)."""
    with contextlib.suppress(pb.error), quiet_c_output():
        pb.disconnect(physicsClientId=client)


def pybullet_data_file(relative: str) -> Path:
    """Absolute path of a file shipped in the ``pybullet_data`` package (the Panda's URDF, for example)."""
    import pybullet_data

    return Path(pybullet_data.getDataPath()) / relative


class Sim:
    """One pybullet physics client.

    Args:
        physics_hz: physics rate in Hz (one ``stepSimulation`` per physics tick).
        solver_iterations: constraint solver iterations per physics tick.
        gravity: gravitational acceleration in m/s^2 (points along -z).
        gui: open the pybullet GUI window (needs a display) instead of a DIRECT client.
        visuals: give static boxes and cylinders visual shapes. Without them nothing can be drawn
            (``rendering.render`` and ``rendering.camera_image`` raise), and cylinders are much cheaper to make:
            TinyRenderer tessellates the visual of each cylinder body anew (docs/design-notes.md#obstacle-visuals).

    Attributes:
        record: what was made in the world, which the parts share (:class:`WorldRecord`).
        actuation, obstacles, rays, rendering: the parts (see the module docstring).
    """

    def __init__(
        self,
        physics_hz: float = 120.0,
        solver_iterations: int = 10,
        gravity: float = GRAVITY,
        gui: bool = False,
        visuals: bool = True,
    ) -> None:
        with quiet_c_output():
            self._cid = pb.connect(pb.GUI if gui else pb.DIRECT)
        if self._cid < 0:
            raise RuntimeError("pybullet could not open a physics client")
        # An env dropped without close() would keep its physics server (tens of MiB) for good: the finalizer
        # disconnects when this Sim is garbage collected. It holds the id, not the Sim, runs at most once (close()
        # calls it too) and not at interpreter exit, where pybullet's module may already be torn down.
        self._finalizer = weakref.finalize(self, _disconnect, self._cid)
        self._finalizer.atexit = False
        self.physics_hz = float(physics_hz)
        self.solver_iterations = int(solver_iterations)
        self._gravity = float(gravity)
        self.record = WorldRecord(self._cid, visuals)
        self.actuation = Actuation(self.record)
        self.obstacles = ObstacleBodies(self.record)
        self.rays = Rays(self.record)
        self.rendering = Rendering(self.record)
        self._empty_world()
        if gui:
            pb.configureDebugVisualizer(pb.COV_ENABLE_GUI, 0, physicsClientId=self._cid)

    def _empty_world(self) -> None:
        """Set the physics parameters and forget every body and shape (the world is empty)."""
        self.record.clear()
        self._inertial_frames: dict[tuple, np.ndarray | None] = {}  # (body, links) -> inertial axes, or None: aligned
        pb.setPhysicsEngineParameter(deterministicOverlappingPairs=1, physicsClientId=self._cid)
        self.set_physics(self.physics_hz, self.solver_iterations)
        pb.setGravity(0.0, 0.0, -self._gravity, physicsClientId=self._cid)

    def set_physics(self, physics_hz: float, solver_iterations: int) -> None:
        """Tick at ``physics_hz`` with ``solver_iterations`` from the next :meth:`step` on (kept by :meth:`clear`)."""
        self.physics_hz, self.solver_iterations = float(physics_hz), int(solver_iterations)
        pb.setPhysicsEngineParameter(fixedTimeStep=1.0 / self.physics_hz, numSolverIterations=self.solver_iterations,
                                     physicsClientId=self._cid)

    @property
    def needs_rebuild(self) -> bool:
        """True once the world holds more memory pybullet cannot free than :data:`MAX_SHAPES` distinct obstacle
        shapes or :data:`MAX_REMOVED_BODIES` removed bodies: time to :meth:`clear` it and build it again."""
        return len(self.record.shapes) > MAX_SHAPES or self.record.removed_bodies > MAX_REMOVED_BODIES

    def clear(self) -> None:
        """Remove every body and shape (``resetSimulation``, which frees their memory) and keep the parameters.

        Body ids start again from 0, so a world built again in the same order has the ids it had the first time.
        """
        pb.resetSimulation(physicsClientId=self._cid)
        self._empty_world()

    # ----------------------------------------------------------------------------------------- lifecycle
    @property
    def client_id(self) -> int:
        """The pybullet ``physicsClientId`` (for benchmarks that replay the raw calls; -1 once closed)."""
        return self._cid

    @property
    def connected(self) -> bool:
        return self._cid >= 0 and pb.isConnected(physicsClientId=self._cid)

    def close(self) -> None:
        """Disconnect the client; safe to call twice. A Sim that is garbage collected unclosed disconnects too."""
        self._finalizer()
        self._cid = self.record.cid = -1

    # ------------------------------------------------------------------------------------------- bodies
    def add_ground(self, visual_size: float, name: str = "ground") -> int:
        """Add an infinite static collision plane at z = 0, drawn as a square; returns its body id.

        The drawn square is a flat untextured box, not pybullet's plane visual: TinyRenderer pays per shaded pixel,
        and the plane visual shades the floor, a large part of every camera image, slower
        (docs/design-notes.md#ground-visual).

        Args:
            visual_size: side of the drawn square in metres.
            name: the ground's name in :attr:`bodies`.
        """
        half = 0.5 * visual_size
        shape = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=self._cid)
        visual = pb.createVisualShape(
            pb.GEOM_BOX, halfExtents=(half, half, 0.0005), visualFramePosition=(0.0, 0.0, -0.0005),
            rgbaColor=(0.85, 0.85, 0.8, 1.0), physicsClientId=self._cid,
        )
        body = self.obstacles.static_bodies(shape, visual, [(0.0, 0.0, 0.0)])[0]
        # drawn as the square; the exact ray caster meets the plane itself
        self.primitives.add(body, "box", (half, half, 0.0005), (0.0, 0.0, 0.0), offset=(0.0, 0.0, -0.0005),
                            solid=False)
        self.record.ground = body
        return self._register(name, body)

    def load_urdf(
        self, name: str, path: str | Path, position: Sequence[float] = (0.0, 0.0, 0.0), fixed_base: bool = False,
        merge_fixed_links: bool = False,
    ) -> int:
        """Load a URDF once and address it by ``name``; returns its body id.

        Cylinders stay true cylinders (``URDF_USE_IMPLICIT_CYLINDER``). By default pybullet turns them into convex
        hulls: polygonal wheels shake the chassis (IMU noise that is not in the model), and the hull with its margin
        reports contact where FCL's exact cylinder still has clearance (docs/design-notes.md#robot-cylinders).

        Args:
            name: the body's name in :attr:`bodies`.
            path: the URDF file.
            position: base position in metres, world frame.
            fixed_base: fix the base to the world.
            merge_fixed_links: make links joined by fixed joints one body (``URDF_MERGE_FIXED_LINKS``), with all
                their collision shapes and visuals: a rigid robot then costs one body a physics tick, not one per
                link. pybullet puts the merged centre of mass at the mass-weighted mean of the links' frame origins
                (not of their centres of mass), so merge only a URDF whose mass sits on links at their centres of
                mass (a rigid airframe's whole mass on its base); the merged links no longer have link indices.

        Raises:
            FileNotFoundError: ``path`` does not exist.
            ValueError: pybullet could not parse the URDF.
        """
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"URDF not found: {path}")
        try:
            with quiet_c_output():
                flags = pb.URDF_USE_IMPLICIT_CYLINDER | (pb.URDF_MERGE_FIXED_LINKS if merge_fixed_links else 0)
                body = pb.loadURDF(str(path), position, useFixedBase=fixed_base, flags=flags, physicsClientId=self._cid)
        except pb.error as exc:
            raise ValueError(f"pybullet could not load URDF {path}: {exc}") from exc
        self.record.made([body])
        return self._register(name, body)

    def add_marker(self, name: str, radius: float, rgba: Sequence[float]) -> int:
        """Add a visual-only disc 1 cm thick, ``radius`` in metres, e.g. a goal marker; returns its body id.

        It has no collision shape: rays, contacts and FCL never see it.
        """
        vis = pb.createVisualShape(
            pb.GEOM_CYLINDER, radius=radius, length=0.01, rgbaColor=rgba, physicsClientId=self._cid
        )
        body = self.obstacles.static_bodies(-1, vis, [(0.0, 0.0, 0.0)], float(np.hypot(radius, 0.005)), rgba)[0]
        self.primitives.add(body, "cylinder", (radius, radius, 0.005), (0.0, 0.0, 0.0), solid=False)
        return self._register(name, body)

    def _register(self, name: str, body: int) -> int:
        if name in self.bodies:
            raise ValueError(f"a body named {name!r} already exists")
        self.bodies[name] = body
        return body

    def set_pose(self, body: int, position: Sequence[float], quaternion: Sequence[float]) -> None:
        """Teleport a body's base inertial frame to ``position`` (metres) and ``quaternion`` (x, y, z, w), world
        frame, and zero its velocity."""
        pb.resetBasePositionAndOrientation(body, position, quaternion, physicsClientId=self._cid)
        pb.resetBaseVelocity(body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), physicsClientId=self._cid)

    def set_base_velocity(self, body: int, linear: Sequence[float], angular: Sequence[float]) -> None:
        """Set a body's base velocity: of its centre of mass (m/s) and its angular velocity (rad/s), world frame."""
        pb.resetBaseVelocity(body, linear, angular, physicsClientId=self._cid)

    # ------------------------------------------------------------------------------------ introspection
    def link_indices(self, body: int) -> dict[str, int]:
        """URDF link name -> pybullet link index (-1 for the base)."""
        base_name = pb.getBodyInfo(body, physicsClientId=self._cid)[0].decode()
        out = {base_name: -1}
        for j in range(pb.getNumJoints(body, physicsClientId=self._cid)):
            info = pb.getJointInfo(body, j, physicsClientId=self._cid)
            out[info[12].decode()] = j
        return out

    def joint_indices(self, body: int) -> dict[str, int]:
        """URDF joint name -> pybullet joint index."""
        return {
            pb.getJointInfo(body, j, physicsClientId=self._cid)[1].decode(): j
            for j in range(pb.getNumJoints(body, physicsClientId=self._cid))
        }

    def base_inertial_offset(self, body: int) -> np.ndarray:
        """Position of the base's centre of mass in the base link frame, metres.

        pybullet reports and sets base poses at the centre of mass, not at the URDF base frame.
        """
        return np.asarray(pb.getDynamicsInfo(body, -1, physicsClientId=self._cid)[3], dtype=float)

    # ---------------------------------------------------------------------------------------- hot path
    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics ticks."""
        for _ in range(n):
            pb.stepSimulation(physicsClientId=self._cid)

    def base_pose(self, body: int) -> tuple[tuple, tuple]:
        """(centre-of-mass position, quaternion (x, y, z, w)), world frame, as pybullet's tuples of floats."""
        return pb.getBasePositionAndOrientation(body, physicsClientId=self._cid)

    def base_state(self, body: int) -> tuple[tuple, tuple, tuple, tuple]:
        """(centre-of-mass position, rotation matrix, linear velocity, angular velocity), world frame, as pybullet's
        tuples of floats: the rotation matrix row by row (9 floats; ``np.reshape(rotation, (3, 3))`` makes the
        matrix). A flying robot reads it every physics tick, where numpy's cost per call outweighs the arithmetic."""
        pos, quat = pb.getBasePositionAndOrientation(body, physicsClientId=self._cid)
        lin, ang = pb.getBaseVelocity(body, physicsClientId=self._cid)
        return pos, pb.getMatrixFromQuaternion(quat), lin, ang

    def link_states(self, body: int, links: Sequence[int]) -> LinkStates:
        """The states of ``links`` (pybullet link indices, each >= 0; the base is :meth:`base_state`'s), in their order,
        from one batched ``getLinkStates`` call with velocities.

        The link frames are rebuilt from the centres of mass: pybullet hands those over in double precision but the
        URDF link frames (``worldLinkFramePosition``) rounded to float32, half a millimetre off 10 km from the origin
        (docs/design-notes.md#link-frames). Rotation matrices come from pybullet's C ``getMatrixFromQuaternion``, one
        call per link, which is faster than a vectorised numpy conversion for the few links a robot tracks
        (docs/design-notes.md#link-rotations).
        """
        rows = pb.getLinkStates(
            body, links, computeLinkVelocity=1, computeForwardKinematics=1, physicsClientId=self._cid
        )
        # one conversion: centre of mass, its offset in the link frame, linear and angular velocity
        flat = np.array([r[0] + r[2] + r[6] + r[7] for r in rows])
        rotation = np.array([pb.getMatrixFromQuaternion(r[1]) for r in rows]).reshape(-1, 3, 3)
        key = (body, tuple(links))
        if key not in self._inertial_frames:  # constant per link: the inertial frame's axes in the link frame
            turned = [r[3] != (0.0, 0.0, 0.0, 1.0) for r in rows]
            self._inertial_frames[key] = (
                np.array([pb.getMatrixFromQuaternion(r[3]) for r in rows]).reshape(-1, 3, 3) if any(turned) else None
            )
        inertial = self._inertial_frames[key]
        if inertial is not None:
            rotation = rotation @ inertial.transpose(0, 2, 1)
        return LinkStates(
            position=flat[:, 0:3] - np.matmul(rotation, flat[:, 3:6, None])[:, :, 0],
            rotation=rotation,
            linear_velocity=flat[:, 6:9],
            angular_velocity=flat[:, 9:12],
        )

    def contact_distances(self, body: int) -> list[tuple[int, float]]:
        """(other body id, signed contact distance in metres) of every contact point of ``body``."""
        return [
            (c[2], c[8]) for c in pb.getContactPoints(bodyA=body, physicsClientId=self._cid)
        ]

    def link_frame(self, body: int, link: int) -> tuple[np.ndarray, np.ndarray]:
        """(origin (3,), rotation (3, 3)) of a link's URDF frame in world coordinates (:func:`.rays.link_frame`)."""
        return link_frame(self._cid, body, link)

    def body_ids(self) -> list[int]:
        """Ids of every body in the world, in increasing order (kept by the record: pybullet's client does not list
        the bodies ``obstacles.static_bodies`` makes in batches)."""
        return sorted(self.record.body_ids)

    def body_names(self) -> dict[int, str]:
        """Body id -> name of every named body (see :meth:`load_urdf`, :meth:`add_ground`, :meth:`add_marker`)."""
        return {body: name for name, body in self.bodies.items()}

    @property
    def bodies(self) -> dict[str, int]:
        """Body id of each body given a name (:meth:`load_urdf`, :meth:`add_ground`, :meth:`add_marker`)."""
        return self.record.bodies

    @property
    def primitives(self) -> PrimitiveTable:
        """The shapes and poses of the boxes, cylinders, ground and markers made here, which the ray-cast camera
        draws and the exact ray caster casts against."""
        return self.record.primitives

    @property
    def culler(self) -> ViewCuller:
        """Bounding spheres and shown colours of the static bodies made here, for culling them from the camera
        frames they cannot appear in."""
        return self.record.culler

    @property
    def visuals(self) -> bool:
        """Whether the obstacles have visual shapes (the constructor's ``visuals``)."""
        return self.record.visuals

    @property
    def gravity(self) -> float:
        """Gravitational acceleration in m/s^2 (along -z)."""
        return self._gravity
