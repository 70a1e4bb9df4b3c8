"""The plain data the parts of an env hand each other: frozen dataclasses of numbers and arrays, no behaviour
beyond arithmetic on their own fields.

This module imports no engine (no pybullet, no FCL, nothing of clutter_gym): a contract
(:mod:`clutter_gym.interfaces`), a task or a test can use these types without a physics client. Frames: world z
up, metres, radians; rotations are 3x3 matrices whose columns are the body axes in world coordinates.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True, slots=True)
class LinkStates:
    """Batched link states, world frame, one row per requested link.

    Attributes:
        position: (n, 3) link frame origins in metres (the URDF link frame, not the inertial frame).
        rotation: (n, 3, 3) link frame orientations (columns are the link axes in world coordinates).
        linear_velocity: (n, 3) velocity of the link's centre of mass in m/s.
        angular_velocity: (n, 3) angular velocity in rad/s.
    """

    position: np.ndarray
    rotation: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray


@dataclass(frozen=True, slots=True)
class RobotState:
    """World-frame state of a robot after a physics step.

    Attributes:
        position: (3,) origin of the URDF base frame, metres.
        rotation: (3, 3) base orientation (columns are the base axes in world coordinates).
        linear_velocity: velocity of the base centre of mass (vx, vy, vz), m/s.
        angular_velocity: base angular velocity (wx, wy, wz), rad/s.
        links: poses and velocities of the links read every step (the IMU and every collision link).
        link_names: names of the rows of ``links``.
        link_index: pybullet index of every link of the robot by URDF name (-1 for the base); constant. Links merged
            into a rigid base (the quadrotor's) have none: their states are among ``links``.
        body: pybullet body id of the robot.
        joint_position: positions of the robot's actuated joints (rad or m), an arm's; empty for the diffbot.
        joint_velocity: their velocities (rad/s or m/s).
    """

    position: np.ndarray
    rotation: np.ndarray
    linear_velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]
    links: LinkStates
    link_names: tuple[str, ...]
    link_index: Mapping[str, int]
    body: int
    joint_position: np.ndarray = field(default_factory=lambda: np.zeros(0))
    joint_velocity: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def yaw(self) -> float:
        """Heading of the base x axis about +z, radians in (-pi, pi]."""
        return math.atan2(self.rotation[1, 0], self.rotation[0, 0])

    def link(self, name: str) -> int:
        """Row of ``links`` that holds link ``name``."""
        return self.link_names.index(name)


@dataclass(frozen=True)
class Obstacle:
    """An upright obstacle: a box or a cylinder standing on the floor or on a surface, static or movable.

    Attributes:
        shape: "box" or "cylinder".
        size: full extents (sx, sy, sz) in metres; a cylinder has sx = sy = 2 * radius.
        position: footprint centre (x, y) in metres.
        yaw: rotation about +z in radians (ignored by the geometry of a cylinder).
        z: height of the bottom face above the floor, metres.
        mass: kilograms of a movable obstacle (uniform density); 0 for a static one.
    """

    shape: str
    size: tuple[float, float, float]
    position: tuple[float, float]
    yaw: float = 0.0
    z: float = 0.0
    mass: float = 0.0

    @property
    def movable(self) -> bool:
        """True for an obstacle the physics moves (it has a mass)."""
        return self.mass > 0.0

    @property
    def volume(self) -> float:
        """m^3."""
        return self.area * self.size[2]

    @property
    def centre(self) -> tuple[float, float, float]:
        """Centre of the obstacle, metres."""
        return (self.position[0], self.position[1], self.z + 0.5 * self.size[2])

    @property
    def radius(self) -> float:
        """Cylinder radius, or the radius of the circle enclosing a box footprint."""
        if self.shape == "cylinder":
            return 0.5 * self.size[0]
        return 0.5 * math.hypot(self.size[0], self.size[1])

    @property
    def area(self) -> float:
        """Footprint area in m^2."""
        if self.shape == "cylinder":
            return math.pi * self.radius**2
        return self.size[0] * self.size[1]

    def distance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed 2D distance (metres) from points (x, y) to the footprint; negative inside."""
        dx, dy = x - self.position[0], y - self.position[1]
        if self.shape == "cylinder":
            return np.hypot(dx, dy) - self.radius
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        qx = np.abs(c * dx + s * dy) - 0.5 * self.size[0]
        qy = np.abs(-s * dx + c * dy) - 0.5 * self.size[1]
        outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        return outside + np.minimum(np.maximum(qx, qy), 0.0)

    def distance3d(self, point: np.ndarray) -> float:
        """Signed distance (metres) from a 3D point to the obstacle's surface; negative inside."""
        dx, dy = point[0] - self.position[0], point[1] - self.position[1]
        dz = abs(point[2] - self.z - 0.5 * self.size[2]) - 0.5 * self.size[2]
        if self.shape == "cylinder":
            radial = math.hypot(dx, dy) - self.radius
            return math.hypot(max(radial, 0.0), max(dz, 0.0)) + min(max(radial, dz), 0.0)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        q = (abs(c * dx + s * dy) - 0.5 * self.size[0], abs(-s * dx + c * dy) - 0.5 * self.size[1], dz)
        return math.sqrt(sum(max(v, 0.0) ** 2 for v in q)) + min(max(q), 0.0)

    def to_dict(self) -> dict[str, Any]:
        if self.shape == "cylinder":
            out = {"shape": "cylinder", "radius": self.radius, "height": self.size[2], "position": list(self.position)}
        else:
            out = {"shape": "box", "size": list(self.size), "position": list(self.position), "yaw": self.yaw}
        if self.z:
            out["z"] = self.z
        return {**out, "mass": self.mass} if self.mass else out


@dataclass(frozen=True, slots=True)
class Contact:
    """A robot link touching or penetrating an obstacle (FCL).

    Attributes:
        link: URDF link name.
        obstacle: index of the obstacle in the scene's obstacle list.
        depth: penetration depth in metres (0 when touching within the tolerance without overlap).
        position: (3,) a contact point in the world frame.
    """

    link: str
    obstacle: int
    depth: float
    position: np.ndarray


@dataclass(frozen=True, slots=True)
class CollisionReport:
    """What FCL (and pybullet, as a cross-check) say about the robot after a step.

    Attributes:
        min_clearance: signed distance from the robot to the nearest obstacle, metres; negative = penetration.
        link_clearance: (L,) signed distance per link with geometry (``CollisionChecker.links``), capped at the
            clearance range; None from a checker made with ``per_link=False``.
        directions: (L, 3) unit vectors from each link's witness point to its obstacle's, world frame (zero
            where the link is out of range or penetrating); None from a checker made with ``per_link=False``.
        closest: (link, obstacle index) of the nearest pair, or None beyond the range.
        witness: (2, 3) witness points (on the link, on the obstacle) of that pair, world frame, or None.
        contacts: robot-link/obstacle pairs within the contact tolerance.
        self_collision: an enabled link pair in self-collision, or None.
        tunneling: shape/obstacle pairs the swept check hit that the end-of-step check found clear.
        pybullet_contacts: pybullet contact points between the robot and obstacles within the tolerance.
        disagreement: exactly one of the two engines reports environment contact.
    """

    min_clearance: float
    link_clearance: np.ndarray | None
    directions: np.ndarray | None
    closest: tuple[str, int] | None
    witness: np.ndarray | None
    contacts: tuple[Contact, ...]
    self_collision: tuple[str, str] | None = None
    tunneling: int = 0
    pybullet_contacts: int = 0
    disagreement: bool = False

    @property
    def n_contacts(self) -> int:
        return len(self.contacts)

    def as_info(self) -> dict[str, object]:
        """The report's entries of a step's ``info`` (docs/envs.md lists them)."""
        return {
            "min_clearance": self.min_clearance,
            "closest_pair": self.closest,
            "witness_points": self.witness,
            "n_contacts": self.n_contacts,
            "max_penetration": max((c.depth for c in self.contacts), default=0.0),
            "self_collision": self.self_collision,
            "tunneling": self.tunneling,
            "pybullet_contacts": self.pybullet_contacts,
            "contact_disagreement": self.disagreement,
        }

    @property
    def in_contact(self) -> bool:
        return bool(self.contacts)


@dataclass(frozen=True)
class DynamicsSample:
    """One episode's dynamics: multipliers of the nominal values, and an absolute restitution."""

    friction_scale: float = 1.0
    restitution: float = 0.0
    mass_scale: float = 1.0
    motor_scale: float = 1.0


@dataclass(frozen=True, slots=True)
class StepOutcome:
    """Reward, its signed terms, the episode-ending flags and the safety cost of one step, by cause (the env puts
    each in ``info["cost_<cause>"]`` and their sum in ``info["cost"]``)."""

    reward: float
    terms: dict[str, float]
    terminated: bool
    is_success: bool
    costs: dict[str, float]

    @property
    def cost(self) -> float:
        return sum(self.costs.values())
