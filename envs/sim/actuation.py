"""Robot actuation: joint motors and states, inverse kinematics, link dynamics, and external forces.

A part of :class:`clutter_gym.sim.Sim` (``sim.actuation``) on the Sim's
:class:`~clutter_gym.sim.world_record.WorldRecord` (its client id). pybullet clears external forces after
every ``stepSimulation``: a robot that flies on them applies them before each physics tick
(:class:`clutter_gym.interfaces.TickedRobot`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pybullet as pb

from clutter_gym.sim.world_record import WorldRecord


class Actuation:
    """Motor commands, joint reads and forces on the robots of one Sim's world."""

    def __init__(self, record: WorldRecord) -> None:
        self._record = record

    def reset_joints(self, body: int, joints: Sequence[int], positions: Sequence[float] | None = None,
                     velocities: Sequence[float] | None = None) -> None:
        """Joint positions (rad or m) and velocities (rad/s or m/s), each zero if not given."""
        for k, j in enumerate(joints):
            pb.resetJointState(body, j, 0.0 if positions is None else positions[k],
                               0.0 if velocities is None else velocities[k], physicsClientId=self._record.cid)

    def set_joint_velocities(
        self, body: int, joints: Sequence[int], velocities: Sequence[float], max_forces: Sequence[float]
    ) -> None:
        """Velocity-controlled motors: target joint velocities (rad/s) under a torque limit (N m)."""
        pb.setJointMotorControlArray(
            body,
            joints,
            pb.VELOCITY_CONTROL,
            targetVelocities=velocities,
            forces=max_forces,
            physicsClientId=self._record.cid,
        )

    def set_joint_positions(
        self,
        body: int,
        joints: Sequence[int],
        positions: Sequence[float],
        velocities: Sequence[float],
        max_forces: Sequence[float],
    ) -> None:
        """Position-controlled motors: PD tracking of target positions and velocities under force limits."""
        pb.setJointMotorControlArray(
            body,
            joints,
            pb.POSITION_CONTROL,
            targetPositions=positions,
            targetVelocities=velocities,
            forces=max_forces,
            physicsClientId=self._record.cid,
        )

    def joint_states(self, body: int, joints: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """(positions, velocities) of ``joints`` in one batched call."""
        rows = pb.getJointStates(body, joints, physicsClientId=self._record.cid)
        flat = np.array([r[:2] for r in rows])
        return flat[:, 0], flat[:, 1]

    def inverse_kinematics(
        self,
        body: int,
        link: int,
        position: Sequence[float],
        orientation: Sequence[float],
        lower: Sequence[float],
        upper: Sequence[float],
        rest: Sequence[float],
    ) -> np.ndarray:
        """Joint positions of every movable joint that put ``link`` at ``position``/``orientation`` (pybullet's
        damped least squares, null space pulled towards ``rest`` within [lower, upper])."""
        lower, upper, rest = ([float(v) for v in values] for values in (lower, upper, rest))
        ranges = [u - lo for lo, u in zip(lower, upper)]
        if not len(lower) == len(upper) == len(rest) == pb.computeDofCount(body, physicsClientId=self._record.cid):
            raise ValueError("inverse_kinematics needs lower, upper and rest for every movable joint")
        # plain lists: pybullet's IK reads numpy arrays out of bounds and crashes
        return np.array(pb.calculateInverseKinematics(
            body, link, [float(v) for v in position], [float(v) for v in orientation], lowerLimits=lower,
            upperLimits=upper, jointRanges=ranges, restPoses=rest, physicsClientId=self._record.cid,
        ))

    def inertial_properties(self, body: int, links: Sequence[int]) -> list[tuple[float, float, tuple]]:
        """(mass kg, lateral friction coefficient, inertia diagonal kg m^2) of each link (-1 = the base)."""
        return [pb.getDynamicsInfo(body, link, physicsClientId=self._record.cid)[:3] for link in links]

    def set_dynamics(
        self, body: int, link: int, mass: float, inertia: Sequence[float], lateral_friction: float, restitution: float
    ) -> None:
        """Set a link's mass (kg), inertia diagonal (kg m^2), friction coefficient and restitution.

        The inertia is passed explicitly: given a mass alone, pybullet recomputes the inertia from the collision
        shape, which is zero for a link without one.
        """
        pb.changeDynamics(
            body,
            link,
            mass=mass,
            localInertiaDiagonal=inertia,
            lateralFriction=lateral_friction,
            restitution=restitution,
            physicsClientId=self._record.cid,
        )

    def set_friction_anchors(self, body: int, links: Sequence[int], on: bool) -> None:
        """Turn Bullet's friction anchors on or off for ``links``: with them on, a contact keeps the point where it
        began and static friction pulls it back there, instead of re-anchoring every tick and letting solver
        residue creep (docs/design-notes.md#standing-still)."""
        for link in links:
            pb.changeDynamics(body, link, frictionAnchor=int(on), physicsClientId=self._record.cid)
        self._record.forget_contacts(body)  # a contact keeps the kind it began with: begin them again
    def centre_of_mass(self, body: int) -> np.ndarray:
        """The whole body's centre of mass (its links' included), world frame, metres."""
        links = range(pb.getNumJoints(body, physicsClientId=self._record.cid))
        masses = [pb.getDynamicsInfo(body, link, physicsClientId=self._record.cid)[0] for link in (-1, *links)]
        centres = [pb.getBasePositionAndOrientation(body, physicsClientId=self._record.cid)[0]]
        centres += [pb.getLinkState(body, link, physicsClientId=self._record.cid)[0] for link in links]
        return np.average(np.array(centres), axis=0, weights=masses)

    def set_damping(self, body: int, linear: float, angular: float) -> None:
        """Set a body's velocity damping (pybullet's default is 0.04 for both, which slows every free body:
        a flying body gets its drag from its own model instead)."""
        pb.changeDynamics(body, -1, linearDamping=linear, angularDamping=angular, physicsClientId=self._record.cid)

    def apply_base_forces(self, body: int, forces: Sequence[Sequence[float]], points: Sequence[Sequence[float]]
                          ) -> None:
        """Apply ``forces`` (N, (fx, fy, fz) each, base frame) at ``points`` (m, from the base's centre of mass, base
        frame) for the next physics tick.

        The base, not the links the points belong to: pybullet turns a link-frame force on a link with that link's
        pose as of the start of the last tick (it refreshes the cached link poses before integrating), so the force
        would point one tick behind the body, a spurious tilt of rate x dt; the base's pose is always current. On a
        rigid body a force acts the same wherever along the body it is applied.
        """
        for force, point in zip(forces, points):
            pb.applyExternalForce(body, -1, force, point, pb.LINK_FRAME, physicsClientId=self._record.cid)

    def apply_base_wrench(self, body: int, force: Sequence[float], torque: Sequence[float]) -> None:
        """Apply a world-frame ``force`` (N) at the base's centre of mass and a world-frame ``torque`` (N m) to the
        base, for the next physics tick. A zero force is not sent (nor the base position read for it): it would add
        nothing."""
        if any(force):
            position, _ = pb.getBasePositionAndOrientation(body, physicsClientId=self._record.cid)
            pb.applyExternalForce(body, -1, force, position, pb.WORLD_FRAME, physicsClientId=self._record.cid)
        pb.applyExternalTorque(body, -1, torque, pb.WORLD_FRAME, physicsClientId=self._record.cid)
