"""What a collision check reports: the robot's clearance and nearest pair, contacts, self-collision and swept hits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
