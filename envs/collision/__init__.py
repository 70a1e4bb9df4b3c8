"""The FCL side: python-fcl is imported only in this package (docs/architecture.md, "Rules").

URDF collision elements (:mod:`clutter_gym.urdf.geometry`) become FCL shapes at a fidelity level
(:mod:`.fidelity`), placed at link poses by a :class:`RobotCollisionModel` that also answers self-collision queries
for the pairs an allowed-collision matrix enables (:mod:`.acm`); a :class:`CollisionChecker` measures the robot
against a scene.
"""

from clutter_gym.collision.acm import AllowedCollisionMatrix, generate_acm, load_acm
from clutter_gym.collision.build import collision_checker
from clutter_gym.collision.checker import CollisionChecker
from clutter_gym.collision.fidelity import FIDELITY_LEVELS, LinkShape, build_link_shapes, check_fidelity
from clutter_gym.collision.obstacles import obstacle_object
from clutter_gym.collision.robot_model import RobotCollisionModel, SelfClearance
from clutter_gym.datatypes import CollisionReport, Contact
from clutter_gym.urdf.geometry import CollisionElement, load_collision_elements
from clutter_gym.urdf.kinematics import UrdfKinematics

__all__ = [
    "FIDELITY_LEVELS",
    "AllowedCollisionMatrix",
    "CollisionChecker",
    "CollisionElement",
    "CollisionReport",
    "Contact",
    "LinkShape",
    "RobotCollisionModel",
    "SelfClearance",
    "UrdfKinematics",
    "build_link_shapes",
    "check_fidelity",
    "collision_checker",
    "generate_acm",
    "load_acm",
    "load_collision_elements",
    "obstacle_object",
]
