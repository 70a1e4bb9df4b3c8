"""The collision checker of a robot, as the envs build it."""

from __future__ import annotations

from collections.abc import Sequence

from clutter_gym.collision.checker import CollisionChecker
from clutter_gym.collision.fidelity import check_fidelity
from clutter_gym.collision.robot_model import RobotCollisionModel
from clutter_gym.interfaces import Robot


def collision_checker(robot: Robot, tracked_links: Sequence[str], fidelity: str, padding: float,
                      contact_tolerance: float, clearance_range: float, control_hz: float, *,
                      self_collision: bool = True, swept_speed: float = 0.2,
                      fixed_links: Sequence[str] = (), per_link: bool = True) -> CollisionChecker:
    """The FCL model of ``robot`` (its base and ``tracked_links``) at ``fidelity``, and its checker, which sweeps
    links between two control steps (``per_link=False``: one that measures only the robot's nearest pair).

    Raises:
        ValueError: an unknown fidelity level, or a padding outside [0, 1] metres.
    """
    model = RobotCollisionModel.from_urdf(robot.urdf_path, check_fidelity(fidelity),
                                          (robot.base_link, *tracked_links), padding, self_collision)
    return CollisionChecker(model, base_link=robot.base_link, contact_tolerance=contact_tolerance,
                            clearance_range=clearance_range, swept_speed=swept_speed, dt=1.0 / control_hz,
                            fixed_links=fixed_links, per_link=per_link)
