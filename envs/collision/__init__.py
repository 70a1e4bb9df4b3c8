"""The FCL side (DESIGN.md rule 5: python-fcl is imported only in this package)."""

from clutter_gym.collision.checker import CollisionChecker, CollisionReport, obstacle_geometry
from clutter_gym.collision.urdf_geometry import CollisionElement, load_collision_elements

__all__ = ["CollisionChecker", "CollisionElement", "CollisionReport", "load_collision_elements", "obstacle_geometry"]
